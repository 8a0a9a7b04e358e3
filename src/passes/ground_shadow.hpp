// Stage 5: soft shadows of the virtual object on the real ground, from the
// dome of lights (ibl/ground_shadow.hpp has the model and its CPU reference).
//
// update() renders, for each light, the object's depth seen from the light
// (an orthographic shadow map: OES_depth_texture where present, depth packed
// into RGBA8 otherwise), then the ground's light fraction into a texture
// laid on the square of ground the shadows can reach. Both are kept until the
// lights or the object change: a still scene renders no shadow map. Every
// frame, drawOnCameraImage() multiplies the camera pixels under that square
// by the fraction (ratio-form differential rendering).
//
// The ground pass draws one light at a time, over only the ground its
// shadow can reach (shadowFootprintNdc), and subtracts its hidden share
// (GL_FUNC_REVERSE_SUBTRACT) from a texture cleared to 1. The composite
// draws only the cells of the square that the shadow darkens
// (darkeningCells).
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "gles/capabilities.hpp"
#include "gles/gl_objects.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/ground_shadow.hpp"
#include "passes/camera_frame_texture.hpp"

namespace probelight::passes {

struct GroundShadowSettings {
  int shadow_map_size_px = 256;       // the object's bounding sphere fills it: 0.3 mm texels for a 7 cm sphere
  int ground_texture_size_px = 256;   // over the square the shadows reach
  double max_region_half_size_m = 0.5;  // lights near the horizon cast shadows this far at most
  // The square's grid in the composite: its vertices follow the lens
  // distortion, and only its cells that the shadow darkens are drawn.
  int region_mesh_segments = 32;
  bool force_packed_depth = false;    // use the RGBA8 path even with OES_depth_texture (tests, comparison)
  // Also keep each light's map of the object's near side, for the object's
  // shadow on itself (a model's self-shadowing; SelfShadowLight).
  bool self_shadow_maps = false;
  ibl::CameraTransfer camera_transfer;  // how the camera's bytes decode to light
};

// One dome light as the object's shader reads it for its shadow on itself:
// the map of the object's near side seen from the light (depth 0 at the
// light's end of its frustum, cleared to 1 where the object is absent),
// and where a point of W falls in it.
struct SelfShadowLight {
  GLuint map = 0;                  // NEAREST; packed RGBA8 depth or a depth texture, as the ground's maps
  glm::mat4 clip_from_world{1.0f};  // LightView::clip_from_world
  glm::vec3 direction_w{0.0f, 0.0f, 1.0f};
  glm::vec3 rgb{0.0f};              // C_i, the dome light's irradiance at normal incidence
  float depth_range_m = 0.0f;       // the frustum's depth
  float width_m = 0.0f;             // and width
};

class GroundShadow {
 public:
  bool init(const gles::Capabilities& capabilities, const GroundShadowSettings& settings, std::string& error);

  // Renders the shadow maps and the ground fraction for these lights and
  // this object. An empty `lights` clears the shadow (nothing is drawn).
  // Leaves the default framebuffer bound with the viewport unset: callers
  // re-bind their target.
  bool update(const std::vector<ibl::ShadowLight>& lights, const ibl::ShadowCaster& caster, std::string& error);

  // Multiplies the camera pixels under the ground square by the fraction, in
  // the bound framebuffer (which holds the camera background, drawn 1:1):
  // only the part of the square the shadow darkens by at least one 8-bit
  // step. Nothing when there is no shadow.
  // exposure_gain: the frame darkened, as drawCameraBackground's. (With
  // a virtual lamp, VirtualLampLight's whole-frame draw gives the ground
  // this fraction instead.)
  bool drawOnCameraImage(const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                         const CameraFrameTexture& camera_frame, std::string& error, double exposure_gain = 1.0);

  bool hasShadow() const { return has_shadow_; }
  // The lights of the last update with their near-side maps (empty unless
  // settings.self_shadow_maps), strongest first.
  const std::vector<SelfShadowLight>& selfShadowLights() const { return self_shadow_lights_; }
  // The object's near side seen from below the horizon, from
  // kFloorLightCount directions kFloorLightElevationDeg down (rgb 0): for
  // the floor's light, which no dome light carries, where the object hides
  // it from itself (the inside of a bowl sees its own walls, not the floor).
  // Made with the near-side maps; empty when there are none.
  static constexpr int kFloorLightCount = 4;
  static constexpr double kFloorLightElevationDeg = -30.0;
  const std::vector<SelfShadowLight>& floorSelfShadows() const { return floor_self_shadows_; }
  int shadowMapSizePx() const { return settings_.shadow_map_size_px; }
  const ibl::GroundRegion& region() const { return region_; }
  // The fraction texture (RGBA8, LINEAR, over region()), for a model's
  // reflection of the floor beside it (ModelRenderer::setNearFloor); only
  // meaningful while hasShadow().
  GLuint fractionTexture() const { return ground_texture_.id(); }
  int shadowPassesLastUpdate() const { return shadow_passes_last_update_; }
  bool packedDepth() const { return packed_depth_; }
  std::string depthStorageDescription() const;

  // The ground texture read back: fraction per texel, row-major from the
  // region's -x, -y corner (texel (i, j) at groundPointOfTexel(i, j)).
  std::optional<std::vector<glm::vec3>> readFraction(std::string& error) const;
  glm::dvec2 groundPointOfTexel(int i, int j) const;
  int groundTextureSizePx() const { return settings_.ground_texture_size_px; }

 private:
  struct ShadowMap {
    gles::Texture depth_or_colour;  // sampled: the depth texture, or the RGBA8 packed colour
    gles::Renderbuffer depth_buffer;  // packed path: depth for the depth test
    gles::Framebuffer framebuffer;
  };
  bool ensureShadowMaps(std::size_t count, std::string& error);
  bool allocateShadowMap(ShadowMap& map, std::string& error);
  bool drawCasterDepth(const glm::mat4& light_clip_from_world, std::string& error);

  GroundShadowSettings settings_;
  bool packed_depth_ = false;
  gles::Program depth_program_;
  gles::Program ground_program_;
  gles::Program composite_program_;
  gles::Buffer footprint_vertices_;  // one light's shadowFootprintNdc
  std::vector<ShadowMap> shadow_maps_;
  std::vector<ShadowMap> near_maps_;  // self_shadow_maps: the object's near side
  std::vector<SelfShadowLight> self_shadow_lights_;
  std::vector<ShadowMap> floor_maps_;  // self_shadow_maps: the object from below the horizon
  std::vector<SelfShadowLight> floor_self_shadows_;
  gles::Texture ground_texture_;
  gles::Framebuffer ground_framebuffer_;
  gles::Buffer caster_vertices_;
  GLsizei caster_vertex_count_ = 0;
  // A mesh's triangles are uploaded once, not at every update (refits);
  // held, so that no other mesh can take its address.
  std::shared_ptr<const std::vector<glm::vec3>> uploaded_mesh_;
  gles::Buffer region_vertices_;
  // The grid cells the composite draws (darkeningCells of the last update).
  gles::Buffer region_indices_;
  GLsizei region_index_count_ = 0;
  ibl::GroundRegion region_;
  bool has_shadow_ = false;
  int shadow_passes_last_update_ = 0;
};

// ground_shadow.frag's constants: the blockers' depth test passes this much
// of the light's depth range behind the ground, and each search and filter
// reads kShadowTaps taps of a unit disc, evenly spread (shadowDiscTaps).
inline constexpr float kShadowBias01 = 2.0f / 1024.0f;
inline constexpr int kShadowTaps = 16;
std::array<glm::vec2, kShadowTaps> shadowDiscTaps();

// The orthographic light view of a directional light that holds a bounding
// sphere (centre, radius) with a little margin: clip = M (x_w, 1). Its
// frustum is `width_m` across and `depth_m` deep, starting just outside the
// sphere on the light's side.
struct LightView {
  glm::dmat4 clip_from_world{1.0};
  double width_m = 0.0;
  double depth_m = 0.0;
  glm::dvec2 ground_depth_gradient_per_uv{0.0};  // d(depth01) / d(uv) of the ground plane z = 0
};
LightView lightViewFor(const glm::dvec3& direction_w, const glm::dvec3& centre_w, double radius_m);

// The ground a light's shadow can reach, as the 4 corners (in order) of a
// convex quad in the ground texture's NDC ([-1, 1]^2 over `region`): the
// ground points whose place in the light's map (`view`, map_size_px square)
// lies within reach of the object. The object fills a disc of radius
// 0.5 / margin of the map's uv about its middle; ground_shadow.frag's taps
// reach at most its blocker search radius, receiver depth x depth_m x
// tan_cone / width_m + one texel, past a point, and a NEAREST read half a
// texel diagonal further. The receiver depth is bounded by its greatest
// value at the region's corners (it is linear on the ground). Outside the
// quad every tap reads the empty map, so the light hides nothing there and
// is not drawn. A light so low that the quad runs off far past the region
// gets the whole square.
std::array<glm::dvec2, 4> shadowFootprintNdc(const LightView& view, double tan_cone, int map_size_px,
                                             const ibl::GroundRegion& region);

// Which cells of a segments x segments grid over the ground texture (n x n
// fractions, row-major) the composite must draw: those holding a texel
// darker than one 8-bit step (below 254.5 / 255 in any channel), or next to
// one, since bilinear reads reach half a texel past it. Row-major, cell
// (i, j) covering texels [i n / segments, (i + 1) n / segments).
std::vector<bool> darkeningCells(const std::vector<glm::vec3>& fraction, int n, int segments);

// The object as triangles (3 vertices each), W metres: a sphere of
// `segments` around (segments / 2 rings), or a box's 12 triangles; each
// counter-clockwise seen from outside (the depth pass culls by it); a
// mesh's own triangles.
std::vector<glm::vec3> casterTriangles(const ibl::ShadowCaster& caster, int segments = 48);

}  // namespace probelight::passes
