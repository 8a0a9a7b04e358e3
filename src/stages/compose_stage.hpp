// The compose stage: over the camera image, the object's shadow on the real
// ground, the object itself lit from the maps (passes/object_compositor),
// and the status bar when something needs saying. It draws into whatever
// framebuffer is bound: the display's, or a render target (`render`).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/status.hpp"
#include "core/types.hpp"
#include "gles/capabilities.hpp"
#include "ibl/ground_shadow.hpp"
#include "ibl/surface_shading.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/model_renderer.hpp"
#include "passes/object_bloom.hpp"
#include "passes/object_blur.hpp"
#include "passes/object_compositor.hpp"
#include "passes/virtual_lamp_light.hpp"
#include "stages/maps_stage.hpp"
#include "stages/pipeline_settings.hpp"
#include "stages/run_report.hpp"
#include "stages/scene_object.hpp"
#include "stages/shadows_stage.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {

// Status text drawn over the frame with OpenCV's Hershey font, re-rendered
// only when the text changes.
class StatusOverlay {
 public:
  const std::vector<std::uint8_t>& render(const std::string& text, int width, int height);

 private:
  std::string text_;
  int width_ = 0;
  int height_ = 0;
  std::vector<std::uint8_t> rgba_;
};

class ComposeStage {
 public:
  static constexpr const char* kStageName = "render";

  // rig: where the ball stands, which the maps see the world from, and
  // camera_transfer how the frame's bytes decode to light: a model's
  // reflection of the floor beside it is read from the maps and the frame
  // (ibl/near_floor.hpp).
  ComposeStage(const SceneObject& object, const CameraIntrinsics& camera, const RigGeometry& rig,
               const ibl::CameraTransfer& camera_transfer, RunReport& report, bool finish_gpu);
  // `storage`: the maps' (the object's shaders decode them).
  Status init(const gles::Capabilities& capabilities, passes::CubeStorage storage);

  // The frame: `track` places the shadow and the object (neither without a
  // tag, nor before the first maps: the object would be black).
  Status draw(const tracking::TagTrackResult& track, const std::string& status, const passes::CameraFrameTexture& frame,
              MapsStage& maps, ShadowsStage& shadows, const ibl::SceneLighting& lighting);
  // Noise matched to the frame's (stages/noise_match_stage.hpp) for the
  // object drawn from now on; null: none. It must outlive the draws.
  void setSensorNoise(const passes::SensorNoiseMatch* noise) { noise_ = noise; }
  // The frame's edge spread (stages/blur_match_stage.hpp) the object is
  // given from now on (passes/object_blur.hpp); none: drawn sharp. With it,
  // the noise goes in after the blur.
  void setBlur(std::optional<double> edge_sigma_px) { blur_edge_sigma_px_ = edge_sigma_px; }
  // The camera's motion over the exposure (stages/motion_match_stage.hpp):
  // the object drawn from now on is smeared along it by the blur layer;
  // none: not smeared.
  void setMotionSmear(std::optional<glm::dvec2> smear_px) { motion_smear_px_ = smear_px; }
  // The camera's exposure and white balance now over those of the maps'
  // frame (stages/response_match_stage.hpp), per channel, for the object
  // drawn from now on.
  void setResponseGain(const glm::dvec3& gain_rgb) {
    response_gain_rgb_ = gain_rgb;
    applyObjectGain();
  }
  // The whole frame darkened as a shorter exposure would darken it, in
  // linear light (stages/lamp_exposure.hpp: the virtual lamp's light would
  // clip); 1: shown as the camera gave it.
  void setExposureGain(double gain) {
    exposure_gain_ = gain;
    applyObjectGain();
  }
  // The lens's glare around the object's light above white
  // (passes/object_bloom.hpp), spread by sigma_px; none: no bloom. The
  // stage `bloom` runs when the object's light can exceed white
  // (stages/bloom_bound.hpp) and skips otherwise (nothing_above_white,
  // no_object, off).
  void setBloom(std::optional<double> sigma_px) { bloom_sigma_px_ = sigma_px; }
  // The virtual lamp (probelight.yaml's virtual_lamp, ibl/virtual_lamp.hpp):
  // with it enabled, the stage `virtual_lamp` lights the real ground
  // around the object (passes/virtual_lamp_light), with the object's
  // shadow from it, and the object itself (as one more of its lights);
  // it skips off, no_object, no_room_light (before the first fit: the
  // lamp's brightness is given against the room's).
  void setVirtualLamp(const VirtualLampConfig& config) { lamp_config_ = config; }
  // The room's light on the ground as the lights were last fitted, in the
  // maps' units (LightsStage::roomGroundIrradiance); none before a fit.
  void setRoomLight(std::optional<glm::dvec3> e_up_maps) { room_e_up_maps_ = e_up_maps; }
  // The display still holds what was drawn last: shown again, not drawn.
  void skip(const std::string& reason) {
    report_.recordStageSkip(kStageName, reason);
    report_.recordStageSkip(kBloomStageName, reason);
    report_.recordStageSkip(kLampStageName, reason);
  }
  static constexpr const char* kBloomStageName = "bloom";
  static constexpr const char* kLampStageName = "virtual_lamp";

 private:
  // The object (sphere, box or model) into the bound framebuffer.
  bool drawObject(const tracking::TagTrackResult& track, MapsStage& maps, const ibl::SceneLighting& lighting,
                  std::string& error);
  // The object's gain: the response's times the exposure's.
  void applyObjectGain() {
    const glm::vec3 gain(response_gain_rgb_ * exposure_gain_);
    compositor_.setResponseGain(gain);
    model_renderer_.setResponseGain(gain);
  }
  // Before the object: the camera's image with the ground's shadow, and
  // the lamp's light on the ground (or the lamp's skip); `lighting` gains
  // the lamp for the object.
  Status drawGround(bool object_drawn, const tracking::TagTrackResult& track, const passes::CameraFrameTexture& frame,
                    ShadowsStage& shadows, ibl::SceneLighting& lighting);
  // After the object: its light above white spread around it, or a skip.
  Status drawBloom(bool object_drawn, const tracking::TagTrackResult& track, MapsStage& maps,
                   const ibl::SceneLighting& lighting);

  SceneObject object_;
  CameraIntrinsics camera_;
  RigGeometry rig_;
  ibl::CameraTransfer camera_transfer_;
  RunReport& report_;
  bool finish_gpu_;
  passes::ObjectCompositor compositor_;
  passes::ModelRenderer model_renderer_;  // for a model
  const passes::SensorNoiseMatch* noise_ = nullptr;
  std::optional<double> blur_edge_sigma_px_;
  std::optional<glm::dvec2> motion_smear_px_;
  glm::dvec3 response_gain_rgb_{1.0};
  double exposure_gain_ = 1.0;
  std::optional<double> bloom_sigma_px_;
  VirtualLampConfig lamp_config_;
  std::optional<glm::dvec3> room_e_up_maps_;
  passes::VirtualLampLight lamp_light_;  // made on the first frame the lamp lights
  bool lamp_ready_ = false;
  gles::Capabilities capabilities_;  // init()'s, for what is made on first use
  std::vector<glm::vec3> caster_triangles_;  // the object's, for the lamp's shadow
  glm::dvec3 lamp_sized_for_ratio_{-1.0};    // the ratio the pool and shadow were made for
  passes::ObjectBloom bloom_;  // made on the first frame that blooms
  passes::ObjectBlurLayer blur_layer_;      // made on the first blurred frame
  passes::SensorNoiseTexture noise_texture_;  // the blur layer's, made on first use
  std::vector<passes::ObjectCompositor::MeshVertex> mesh_;  // a box's triangles (empty for a sphere)
  StatusOverlay overlay_;
};

}  // namespace probelight
