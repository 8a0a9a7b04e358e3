// The virtual lamp's light on the real ground (issue 19, seed D), with the
// object's shadow from it: ibl/virtual_lamp.hpp has the model.
//
// updateShadow() draws the object's triangles flattened onto the ground
// from the lamp (a planar projection: exact for a point light and a flat
// floor, for any mesh) into a mask over the square its shadow fills, 0
// where the lamp is hidden; it is kept until the lamp or the object move.
// The draws then pass over the frame: each pixel's camera ray (through the
// lens, from a grid of rays made once) meets the ground, and a ground pixel
// gets the lamp's light: the camera pixel, decoded, times the exposure gain
// and (the dome's shadow fraction + the lamp's ratio), encoded
// (virtual_lamp.frag). They stand in for the background's and the ground
// shadow's draws. (A grid laid on the ground instead, as the shadow's,
// reaches behind the camera when the lamp lights far, where its triangles
// cannot be projected.)
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "gles/capabilities.hpp"
#include "gles/gl_objects.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/ground_shadow.hpp"
#include "ibl/virtual_lamp.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/ground_shadow.hpp"

namespace probelight::passes {

struct VirtualLampLightSettings {
  int shadow_mask_size_px = 512;  // over the square the object's shadow from the lamp fills
  int grid_columns = 16;          // the frame's grid of rays (rows in proportion)
  ibl::CameraTransfer camera_transfer;
};

// The window rectangle (gl_FragCoord's: x0, y0, x1, y1) holding the rig's
// ball and post (their box, down to the ground), with a margin; the whole
// plane when a corner is behind the camera.
glm::vec4 rigWindowRect(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const RigGeometry& rig);

class VirtualLampLight {
 public:
  // `camera`: the frame's calibration, for the grid of rays.
  bool init(const gles::Capabilities& capabilities, const VirtualLampLightSettings& settings,
            const CameraIntrinsics& camera, std::string& error);

  // The lamp, and the object's shadow from it, drawn into the mask over
  // the square its triangles' shadow fills (a texel a fraction of a
  // millimetre for a hand-sized object). `caster_triangles_w`: the
  // object's triangles (casterTriangles), uploaded when they change (by
  // address and size). A lamp not above every vertex casts no shadow drawn
  // (the projection needs the object below the lamp): false in
  // castsShadow().
  bool updateShadow(const ibl::VirtualLamp& lamp, const std::vector<glm::vec3>& caster_triangles_w,
                    std::string& error);
  bool castsShadow() const { return casts_shadow_; }

  struct Frame {
    glm::dvec3 ratio_at_one_metre_rgb{0.0};  // ibl::lampRatioAtOneMetre
    const GroundShadow* dome_shadow = nullptr;  // its fraction, where it has a shadow
    double exposure_gain = 1.0;
  };
  // Over the bound framebuffer (the frame 1:1), in two draws that stand
  // in for the background's and the ground shadow's (drawOnCameraImage):
  // drawSmooth, the whole frame: the camera's image times the exposure
  // gain, with the ground darkened by the dome's shadow and lit by the
  // lamp, unshadowed; drawDetail, cut to the frame's rectangle about the
  // object's shadow from the lamp and the rig's ball and post (which are
  // not ground), everything: the dome's shadow, the lamp hidden by the
  // object, the rig in front. (One draw of everything over the frame cost
  // 16 ms on llvmpipe, which pays for every branch at every pixel.)
  bool drawSmooth(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const CameraFrameTexture& camera_frame,
                  const RigGeometry& rig, const Frame& frame, std::string& error) {
    return drawPass(false, camera, pose, camera_frame, rig, frame, error);
  }
  bool drawDetail(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const CameraFrameTexture& camera_frame,
                  const RigGeometry& rig, const Frame& frame, std::string& error) {
    return drawPass(true, camera, pose, camera_frame, rig, frame, error);
  }
 private:
  bool drawPass(bool detail, const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                const CameraFrameTexture& camera_frame, const RigGeometry& rig, const Frame& frame, std::string& error);

  VirtualLampLightSettings settings_;
  gles::Program shadow_program_;
  // The whole frame (a point light's, a spot's); near the object and the rig.
  gles::Program point_program_, light_program_, detail_program_;
  gles::Texture shadow_mask_;
  gles::Framebuffer shadow_framebuffer_;
  gles::Buffer caster_vertices_;
  const glm::vec3* uploaded_data_ = nullptr;
  std::size_t uploaded_size_ = 0;
  gles::Buffer grid_vertices_, grid_indices_;  // NDC and the camera ray, per vertex
  GLsizei grid_index_count_ = 0;
  ibl::VirtualLamp lamp_;
  ibl::GroundRegion mask_square_;  // what shadow_mask_ covers
  bool casts_shadow_ = false;
};

}  // namespace probelight::passes
