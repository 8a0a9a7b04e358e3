// Stage 4 for a user's model: a glTF model (model::MeshModel) placed in W,
// drawn with its metallic-roughness materials lit from the environment maps
// (shaders-gles/model_object.frag; its CPU reference is
// ibl::shadeMetallicRoughness).
//
// init() uploads everything once: vertices already placed in W (the
// placement is fixed while the program runs), flat normals where the file
// has none (glTF requires them), tangents from the UVs where a normal map
// needs them and the file has none, 16-bit indices where they suffice,
// 32-bit ones with OES_element_index_uint, otherwise the primitive cut into
// pieces 16-bit indices can address. Textures become mipmapped RGBA8, resized
// to powers of two where the GPU lacks OES_texture_npot (GLES2 core mipmaps
// and repeats only those) and to max_texture_size_px at most.
//
// Each material gets a program for what it uses: its textures and their UV
// sets, its vertex colours, its alpha mode, double-sidedness, and the span of
// the specular ladder (mirror, glossy maps, diffuse) its roughness can reach
// over its texture, so a matte material reads no mirror map and a mirror no
// glossy one (stages/scene_object.hpp's modelReadsGlossy tells the maps
// stage whether to make them at all).
//
// Edges (passes/edge_antialiasing.hpp): with edge_samples > 1 the model's
// silhouette is anti-aliased against the video, by the framebuffer's own
// multisampling, GL_EXT_multisampled_render_to_texture, or (core GLES2) a
// supersampled layer; the model is then drawn into a layer of its own,
// depth-tested against itself, and composited over the frame.
//
// Order: opaque and masked primitives first, then blended ones back to
// front (by their centres, from the eye), without depth writes. Blending is
// over the sRGB-encoded camera image, as GLES2 without sRGB framebuffers
// does it.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "gles/capabilities.hpp"
#include "gles/gl_objects.hpp"
#include "ibl/environment_brdf.hpp"
#include "ibl/surface_shading.hpp"
#include "model/mesh_model.hpp"
#include "passes/edge_antialiasing.hpp"
#include "ibl/color_transfer.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/camera_response.hpp"
#include "passes/environment_maps.hpp"
#include "passes/ground_shadow.hpp"

namespace probelight::passes {

struct ModelRendererSettings {
  double near_m = 0.01;
  double far_m = 50.0;
  // Larger images are shrunk to this: a 2048^2 RGBA8 texture with its mip
  // chain is 22 MB of a board's GPU memory.
  int max_texture_size_px = 2048;
  // Testing the paths a board without these extensions takes.
  bool force_short_indices = false;    // as if OES_element_index_uint were absent
  bool force_power_of_two = false;     // as if OES_texture_npot were absent
  // Samples a pixel for the model's edges against the video
  // (chooseEdgeAntialiasing): 4 is MSAA 4x where the GPU has it, else a
  // 2 x 2 supersampled layer (4x the model's fragment work); 16 a 4 x 4 one;
  // 1 off: the model drawn straight into the frame, one sample a pixel. The
  // kiosk asks for kKioskEdgeSamples; off is this pass's own default so that
  // a bare ModelRenderer blends exactly as a direct draw (through the 8-bit
  // layer a blended material's colour is rounded once more, 0.5 code).
  int edge_samples = 1;
  // How the frame's bytes encode light: the model leaves in that encoding
  // (camera_response.glsl), and the frame's floor in its reflections is
  // decoded through it.
  ibl::CameraTransfer camera_transfer;
};

// What stages/compose_stage (probelight run, render) asks for.
constexpr int kKioskEdgeSamples = 4;

// What init() made, for the report and the bench.
struct ModelUploadStats {
  std::size_t triangles = 0;
  std::size_t draw_pieces = 0;     // glDrawElements calls a frame
  std::size_t split_pieces = 0;    // pieces made because 16-bit indices could not address a primitive
  std::size_t textures = 0;
  std::uint64_t texture_bytes = 0;  // with mip chains
  std::uint64_t vertex_bytes = 0;
  std::uint64_t index_bytes = 0;
  bool short_indices_only = true;   // no 32-bit index buffer was needed
  double upload_ms = 0.0;
  // How the edges are anti-aliased (prepareEdges, and again by each draw
  // for its framebuffer), and the GPU memory its layer holds.
  EdgeAntialiasing edges;
  std::uint64_t edge_layer_bytes = 0;
};

class ModelRenderer {
 public:
  bool init(const gles::Capabilities& capabilities, CubeStorage storage, const model::MeshModel& model,
            const glm::dmat4& world_from_model, const ModelRendererSettings& settings, std::string& error);

  // Draws the model into the bound framebuffer (whose viewport covers the
  // camera image), depth-tested against what is there, or, with edge
  // anti-aliasing through a layer, against itself and composited over it.
  // Uses the glossy maps when environment.glossyWritten().
  bool draw(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const ibl::SceneLighting& lighting,
            EnvironmentMaps& environment, std::string& error);

  // The object's shadow on itself from these lights (GroundShadow with
  // self_shadow_maps; strongest first), until set again; null or empty: none.
  // As many are read as the GPU's texture units and fragment uniforms allow
  // (selfShadowLightsRead says how many the last draw read).
  // `floor`: GroundShadow::floorSelfShadows, for the floor's light the
  // model hides from itself (null or empty: the floor's light is never
  // hidden). They take their texture units before the weakest dome lights.
  void setSelfShadow(const std::vector<SelfShadowLight>* lights, int map_size_px, bool packed_depth,
                     const std::vector<SelfShadowLight>* floor = nullptr);
  int selfShadowLightsRead() const { return self_shadow_lights_read_; }

  // The floor beside the model in its reflections (ibl/near_floor.hpp):
  // specular directions that go down are read where the maps show the
  // ground they meet (the mirror rung from the camera's frame where it
  // shows it), darkened by the shadow's fraction there. Until set again;
  // off by default (the maps read as they are).
  struct NearFloor {
    bool enabled = false;
    glm::dvec3 ball_centre_w{0.0};  // the ball the maps were made from (seen by draw()'s camera)
    double ball_radius_m = 0.0;
    const GroundShadow* shadow = nullptr;             // null, or without a shadow: not darkened
    const CameraFrameTexture* camera_frame = nullptr;  // null: the maps alone (decoded with settings' camera_transfer)
  };
  void setNearFloor(const NearFloor& near_floor);

  // Noise matched to the frame's for the draws from now on; null: none. It
  // must outlive them. In the model's shader, or at the resolve of a
  // supersampled edge layer (EdgeLayer::addsNoiseAfterResolve).
  void setSensorNoise(const SensorNoiseMatch* noise) { sensor_noise_ = noise; }
  // The exposure and white balance now over the maps' (1: unmoved), which
  // the model's linear colour is multiplied by as it leaves
  // (camera_response.glsl).
  void setResponseGain(const glm::vec3& gain_rgb) { response_gain_rgb_ = gain_rgb; }
  // true: draw() writes the model's light beyond white for the bloom
  // (passes/object_bloom.hpp), straight into the bound target, no noise.
  void setBloomBrightPass(bool on) { bloom_bright_pass_ = on; }

  // Chooses the edge anti-aliasing for frames of width_px x height_px drawn
  // into a framebuffer with target_samples (GL_SAMPLES; 0 single-sampled)
  // and allocates its layer, so that stats().edges says what the GPU gave
  // before the first frame. draw() calls it itself for its framebuffer; a
  // layer the GPU refuses falls back to the next strategy, with a warning.
  bool prepareEdges(int width_px, int height_px, int target_samples, std::string& error);

  const ModelUploadStats& stats() const { return stats_; }
  // One line each, said once: what the renderer had to leave out or change.
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  enum Slot { kBaseColor, kMetallicRoughness, kNormal, kOcclusion, kEmissive, kSlotCount };
  struct MaterialState {
    model::Material material;
    float min_roughness = 1.0f, max_roughness = 1.0f;
    std::array<const gles::Texture*, kSlotCount> textures{};  // null: slot unused
  };
  // A piece's vertex format and material, shared by the pieces a primitive is cut into.
  struct PieceFormat {
    GLsizei stride_bytes = 0;
    // Byte offsets into a vertex; -1 where the piece has no such attribute.
    int tangent_offset = -1, uv0_offset = -1, uv1_offset = -1, color_offset = -1;
    std::size_t material = 0;      // into materials_
    std::array<bool, kSlotCount> slot_used{};  // textures this piece can map (its UV set exists)
    std::string defines;           // everything but the rungs
    glm::vec3 centre_w{0.0f};
  };
  struct Piece : PieceFormat {
    gles::Buffer vertices;
    gles::Buffer indices;
    GLsizei index_count = 0;
    GLenum index_type = GL_UNSIGNED_SHORT;
  };

  bool uploadPrimitive(const model::Primitive& primitive, std::size_t material, const glm::dmat4& world_from_model,
                       std::string& error);
  const gles::Texture* textureFor(const model::MeshModel& model, const model::TextureSlot& slot, std::string& error);
  const gles::Program* programFor(const Piece& piece, int rung_first, int rung_last, int glossy_levels,
                                  int self_shadow_lights, int self_shadow_floor, bool floor_shadow, bool floor_camera,
                                  bool noise_in_shader, std::string& error);
  // A set of self-shadow lights' maps and uniforms (`prefix`_map, _row0..2,
  // _direction, _rgb, _texel), from texture unit `unit` on (advanced).
  void bindSelfShadowLights(const gles::Program& program, const std::string& prefix,
                            const std::vector<SelfShadowLight>& lights, int count, int& unit) const;
  bool drawPiece(const Piece& piece, const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                 const ibl::SceneLighting& lighting, EnvironmentMaps& environment,
                 const std::vector<double>& rung_alphas, std::string& error);

  ModelRendererSettings settings_;
  gles::Capabilities capabilities_;
  CubeStorage storage_ = CubeStorage::kSrgb8;
  std::vector<MaterialState> materials_;
  std::vector<Piece> pieces_;
  std::map<std::tuple<int, int, int, int, bool>, gles::Texture> textures_;  // image, wrap s, wrap t, mag nearest
  std::map<std::string, gles::Program> programs_;
  gles::Texture brdf_table_;
  int brdf_table_size_ = 0;
  const std::vector<SelfShadowLight>* self_shadow_ = nullptr;
  const std::vector<SelfShadowLight>* self_shadow_floor_ = nullptr;
  int self_shadow_map_size_px_ = 0;
  bool self_shadow_packed_ = false;
  int self_shadow_lights_read_ = 0;
  NearFloor near_floor_;
  const SensorNoiseMatch* sensor_noise_ = nullptr;
  glm::vec3 response_gain_rgb_{1.0f};
  bool bloom_bright_pass_ = false;
  glm::vec3 dome_rgb_scale_{1.0f};  // the draw's SceneLighting::dome_rgb_scale
  SensorNoiseTexture noise_texture_;  // made on the first draw with noise
  ModelUploadStats stats_;
  std::vector<std::string> warnings_;
  // What chooseEdgeAntialiasing said for the frame size below (the layer may
  // have fallen back from it: stats_.edges is what is used).
  EdgeAntialiasing edge_request_;
  int edge_width_px_ = 0, edge_height_px_ = 0;
  EdgeLayer edge_layer_;
  // Every vertex lies in this box (W): what the layer is cut to.
  glm::dvec3 bounds_min_w_{0.0}, bounds_max_w_{0.0};
};

// KHR_texture_transform's uv' = T R S uv as the 3x3 matrix the shader applies.
glm::mat3 textureTransformMatrix(const model::TextureSlot& slot);

// The range of roughness a material reaches: its factor times the least and
// the greatest G of its metallic-roughness image (the factor alone without
// one). The GPU's filtering only interpolates texels, so it stays within.
std::pair<float, float> materialRoughnessRange(const model::Material& material, const model::MeshModel& model);

// The power of two nearest to size (in ratio), at most max_size (itself a power of two or not).
int nearestPowerOfTwo(int size, int max_size);

}  // namespace probelight::passes
