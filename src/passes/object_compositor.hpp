// Stage 4: the composed frame. Draws into whatever framebuffer is bound
// (normally a gles::RenderTarget of the camera's size), under the screen
// convention: image row 0 at NDC y = +1.
//
// Per frame: drawCameraBackground (also clears depth), drawSphereObject for
// each object, then drawOverlayRGBA for status text.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "gles/capabilities.hpp"
#include "gles/gl_objects.hpp"
#include "ibl/ground_shadow.hpp"
#include "ibl/surface_shading.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"

namespace probelight::passes {

struct ObjectCompositorSettings {
  // 64 x 32 facets: the chord of a 100 px-radius silhouette sags by
  // 100 * (1 - cos(pi / 64)) = 0.12 px, and facet normals are off by at most
  // ~(pi / 64)^2 / 8 * tan(view angle) rad.
  int sphere_longitude_segments = 64;
  int sphere_latitude_segments = 32;
  double near_m = 0.01;
  double far_m = 50.0;
};

class ObjectCompositor {
 public:
  // `storage` must be the EnvironmentMaps' storage the object will be lit with.
  bool init(const gles::Capabilities& capabilities, const ObjectCompositorSettings& settings, CubeStorage storage,
            std::string& error);

  // The camera frame, unmodified and upright, over the current viewport.
  // Clears the depth buffer (start of a frame) and leaves depth test off.
  void drawCameraBackground(const CameraFrameTexture& camera_frame);

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

  // Blends straight-alpha RGBA (top row first, sRGB bytes) over the whole viewport.
  bool drawOverlayRGBA(const std::uint8_t* rgba, int width, int height, std::string& error);

 private:
  // Uniforms, textures and state shared by the object programs.
  bool prepareShading(const gles::Program& program, const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                      const ibl::SurfaceMaterial& material, const ibl::SceneLighting& lighting,
                      EnvironmentMaps& environment, std::string& error);

  ObjectCompositorSettings settings_;
  CubeStorage storage_ = CubeStorage::kSrgb8;
  gles::Program image_program_;
  gles::Program sphere_program_;
  gles::Program mesh_program_;
  gles::Buffer mesh_vertices_;
  gles::FullScreenQuad quad_;
  gles::Buffer sphere_vertices_;
  gles::Buffer sphere_indices_;
  GLsizei sphere_index_count_ = 0;
  gles::Texture overlay_;
  int overlay_width_ = 0;
  int overlay_height_ = 0;
};

// A box standing on the ground (ibl::ShadowCaster of Shape::kBox) as 12
// flat-shaded triangles with outward normals.
std::vector<ObjectCompositor::MeshVertex> boxMesh(const ibl::ShadowCaster& box);

}  // namespace probelight::passes
