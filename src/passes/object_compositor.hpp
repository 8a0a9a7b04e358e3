// Stage 4: the composed frame. Draws into whatever framebuffer is bound
// (normally a gles::RenderTarget of the camera's size), under the screen
// convention: image row 0 at NDC y = +1.
//
// Per frame: drawCameraBackground (also clears depth), drawSphereObject for
// each object, then drawOverlayRGBA for status text.
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
#include "ibl/ground_shadow.hpp"
#include "ibl/surface_shading.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/camera_response.hpp"
#include "passes/environment_maps.hpp"

namespace probelight::passes {

// The reflection ladder's rungs (ibl/surface_shading.hpp) as the maps the
// object shader reads: kinds 0 mirror, 1 glossy 0, 2 glossy 1, 3 diffuse.
// R = mix(lower, upper, toward_upper); upper_kind is -1 when the blend reads
// only the lower rung (toward_upper 0).
struct ReflectionRungs {
  int lower_kind = 0;
  int upper_kind = -1;
  float toward_upper = 0.0f;
};
ReflectionRungs reflectionRungsFor(float glossiness, int glossy_levels);

struct ObjectCompositorSettings {
  // The sphere is tessellated for its size on screen (sphereSegmentsFor):
  // N longitude x N / 2 latitude facets, the fewest of kSphereSegmentSteps
  // whose chords sag by at most this much off the true silhouette (a
  // 100 px-radius sphere gets 48 x 24: 100 (1 - cos(pi / 48)) = 0.21 px).
  // Shading uses the interpolated, renormalised sphere normal, so only the
  // outline depends on it. Small triangles are what llvmpipe (and tiled
  // GPUs) pay for per triangle; 4,096 one-pixel ones were half of `render`.
  double max_silhouette_sag_px = 0.25;
  double near_m = 0.01;
  double far_m = 50.0;
  // How the frame's bytes encode light: the object leaves in the same
  // encoding (camera_response.glsl).
  ibl::CameraTransfer camera_transfer;
};

class ObjectCompositor {
 public:
  // `storage` must be the EnvironmentMaps' storage the object will be lit with.
  bool init(const gles::Capabilities& capabilities, const ObjectCompositorSettings& settings, CubeStorage storage,
            std::string& error);

  // The camera frame, unmodified and upright, over the current viewport.
  // Clears the depth buffer (start of a frame) and leaves depth test off.
  // exposure_gain: the frame darkened (< 1) as a shorter exposure would
  // darken it, in linear light (stages/lamp_exposure.hpp); 1: its bytes.
  void drawCameraBackground(const CameraFrameTexture& camera_frame, double exposure_gain = 1.0);
  // What drawCameraBackground does besides the image: for a pass that
  // draws the whole frame itself (passes/virtual_lamp_light).
  void clearDepth();

  // A sphere of radius_m at centre_w (W), lit by ibl::shadeSurface with the
  // environment maps, depth-tested. The current viewport must cover the whole
  // camera image (camera.width_px x camera.height_px). The reflection term
  // uses the glossy maps when environment.glossyWritten() (ibl::needsGlossy
  // says when the app must call updateGlossy), else the ladder mirror -> diffuse.
  bool drawSphereObject(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, glm::dvec3 centre_w,
                        double radius_m, const ibl::SurfaceMaterial& material, const ibl::SceneLighting& lighting,
                        EnvironmentMaps& environment, std::string& error);

  // Triangles (3 vertices each) with their normals, in W, shaded as the
  // sphere is: for objects other than spheres (a box, later meshes).
  struct MeshVertex {
    glm::vec3 position_w;
    glm::vec3 normal_w;
  };
  bool drawMeshObject(const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                      const std::vector<MeshVertex>& triangles, const ibl::SurfaceMaterial& material,
                      const ibl::SceneLighting& lighting, EnvironmentMaps& environment, std::string& error);

  // Noise matched to the frame's for the objects drawn from now on; null:
  // none. Kept by pointer: it must outlive those draws.
  void setSensorNoise(const SensorNoiseMatch* noise) { sensor_noise_ = noise; }
  // The exposure and white balance now over the maps' (1: unmoved), which
  // the object's linear colour is multiplied by as it leaves
  // (camera_response.glsl).
  void setResponseGain(const glm::vec3& gain_rgb) { response_gain_rgb_ = gain_rgb; }
  // true: the draws write the object's light beyond white for the bloom
  // (passes/object_bloom.hpp, bloomBrightPassDefines), with no noise.
  void setBloomBrightPass(bool on) { bloom_bright_pass_ = on; }

  // Blends straight-alpha RGBA (top row first, sRGB bytes) over the whole viewport.
  bool drawOverlayRGBA(const std::uint8_t* rgba, int width, int height, std::string& error);

 private:
  enum class ObjectShape { kSphere, kMesh };
  // The shape's program for this material's rungs, in use, with the
  // uniforms, textures and state shared by the object programs; null on
  // failure (error says why).
  const gles::Program* prepareShading(ObjectShape shape, const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                                      const ibl::SurfaceMaterial& material, const ibl::SceneLighting& lighting,
                                      EnvironmentMaps& environment, std::string& error);

  // The shading program for a shape, the ladder's rungs
  // (reflectionRungsFor), whether it adds noise and whether it is the
  // bloom's bright pass (then no noise), built on first use and kept.
  const gles::Program* shadingProgram(ObjectShape shape, const ReflectionRungs& rungs, bool match_noise,
                                      bool bloom_bright_pass, std::string& error);

  ObjectCompositorSettings settings_;
  CubeStorage storage_ = CubeStorage::kSrgb8;
  gles::Program image_program_;
  gles::Program darkened_image_program_;  // the camera background at an exposure gain
  std::map<std::tuple<ObjectShape, int, int, bool, bool>, gles::Program> shading_programs_;
  const SensorNoiseMatch* sensor_noise_ = nullptr;
  glm::vec3 response_gain_rgb_{1.0f};
  bool bloom_bright_pass_ = false;
  SensorNoiseTexture noise_texture_;  // made on the first frame with noise
  gles::Buffer mesh_vertices_;
  gles::FullScreenQuad quad_;
  struct SphereMesh {
    int segments = 0;  // longitude; latitude is half
    gles::Buffer vertices;
    gles::Buffer indices;
    GLsizei index_count = 0;
  };
  std::vector<SphereMesh> sphere_meshes_;  // one per kSphereSegmentSteps
  gles::Texture overlay_;
  int overlay_width_ = 0;
  int overlay_height_ = 0;
};

// Longitude segment counts the sphere is built with (latitude: half).
inline constexpr int kSphereSegmentSteps[] = {8, 12, 16, 24, 32, 48, 64, 96, 128};

// The fewest of kSphereSegmentSteps whose chord, on a silhouette of
// radius_px, sags by at most max_sag_px: radius_px (1 - cos(pi / N)); the
// most when none does (or the radius is not finite).
int sphereSegmentsFor(double radius_px, double max_sag_px);

// Upper bound of the silhouette radius in pixels of a sphere of radius_m
// whose centre is depth_m ahead of the camera: focal_px * radius_m /
// (depth_m - radius_m) (the cone's tangent, above the distortion-free
// projection's half width); infinity when the camera is within a radius.
double sphereSilhouetteRadiusBoundPx(double focal_px, double radius_m, double depth_m);

// A box standing on the ground (ibl::ShadowCaster of Shape::kBox) as 12
// flat-shaded triangles with outward normals.
std::vector<ObjectCompositor::MeshVertex> boxMesh(const ibl::ShadowCaster& box);

}  // namespace probelight::passes
