// The lights stage: when to recalibrate (stages/lighting_state_machine: the
// button, start-up, a change in the ground's light), the exposure bracket a
// fit takes where the ball clips (stages/bracket_controller, merged by
// stages/bracket_merge), the fit itself (ibl/lighting_fit: white border,
// post, clipped lights, dome, dominant light), the clipped lights followed
// between fits (stages/clipped_light_follower), the dome faded to its new
// place (stages/light_transition), and the lighting kept across restarts
// (stages/state_store).
//
// Per frame the kiosk calls admit() first (a bracket's frames, and the ones
// after it still at bracket exposures, do not go down the pipeline), then,
// after the maps stage, run().
#pragma once

#include <chrono>
#include <cmath>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "capture/exposure_control.hpp"
#include "core/status.hpp"
#include "core/types.hpp"
#include "ibl/light_dome.hpp"
#include "ibl/lighting_fit.hpp"
#include "ibl/surface_shading.hpp"
#include "stages/bracket_controller.hpp"
#include "stages/bracket_merge.hpp"
#include "stages/clipped_light_follower.hpp"
#include "stages/frame_context.hpp"
#include "stages/light_transition.hpp"
#include "stages/frame_response.hpp"
#include "stages/lighting_state_machine.hpp"
#include "stages/maps_stage.hpp"
#include "stages/pipeline_settings.hpp"
#include "stages/run_report.hpp"
#include "stages/state_store.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {

// What admit() says of an arriving frame.
struct FrameAdmission {
  bool run_pipeline = true;
  std::string kept_status;  // when not: the status the kept frame is shown with
};

class LightsStage {
 public:
  static constexpr const char* kFitStageName = "fit_lights";
  static constexpr const char* kRescaleStageName = "clipped_rescale";
  static constexpr const char* kMergeStageName = "bracket_merge";

  LightsStage(const PipelineSettings& settings, const RigGeometry& rig, const CameraIntrinsics& camera,
              ExposureControl& camera_control, RunReport& report, std::ostream& log);
  // The bracket's tag tracker: bad tracking settings are bad input.
  Status init();
  // The lighting kept from the last run (state.dir), shown from the first
  // frame and what a long press goes back to: a missing file is normal
  // (first boot), an unreadable one is said and the kiosk starts without it.
  void loadStoredLighting();

  // Every frame, first.
  FrameAdmission admit(const FrameContext& ctx);
  // After a frame admit() kept back has been shown: its time is the
  // bracket's, and a bracket that is over is merged and fitted.
  // (The maps take the bracket into their probe: environment_maps.merge_views.)
  Status afterKeptFrame(const FrameContext& ctx, MapsStage& maps);
  // After the maps stage: clipped lights followed, a change in the light
  // noticed, the recalibration advanced, and the lights fitted when it
  // completes.
  Status run(FrameContext& ctx, MapsStage& maps);

  // A short press: true when it starts a recalibration (the maps must then
  // be made fresh); a press during one, or during its bracket, is ignored.
  bool onButtonPress();
  // A long press: back to the stored lighting (a fit that went wrong is undone).
  void onLongPress();
  // The camera went away: its next stream starts with auto exposure.
  void onCameraLost();
  // A bracket cut short (the run's end, a lost camera) is fitted from what
  // it has.
  Status finishPendingBracket(std::uint64_t frame_number, MapsStage& maps);

  bool recalibrating() const { return machine_.state() == AppState::kRecalibrating; }
  bool bracketPending() const { return bracket_.pending(); }
  // What the object is shaded with: the dominant light's highlight and the
  // clipped lights, in the maps' units (stages/frame_response.hpp: the fit
  // frame's exposure and white balance brought to the maps' frame's), and
  // the factor that brings the dome's irradiances there too.
  const ibl::SceneLighting& sceneLighting() const { return shown_lighting_; }
  // The room's irradiance on the ground (facing up) as the lights were
  // last fitted, clipped lights included, in the maps' units; none before
  // a fit. What a virtual lamp's brightness is given against
  // (ibl/virtual_lamp.hpp).
  std::optional<glm::dvec3> roomGroundIrradiance() const { return room_e_up_maps_; }
  // The response of the frame the lights in use were fitted in, for the
  // maps' clip level (MapsStage::setLightsFittedAt); none before any
  // lights and while recalibrating (the fit reads the 8-bit maps as shown).
  std::optional<FrameResponse> clipReference() const {
    if (transition_.empty() || recalibrating() || bracket_.pending()) return std::nullopt;
    return fit_response_;
  }
  // The dome shown at `now_s` (fading after a fit); empty before any.
  std::vector<ibl::DomeLight> domeAt(double now_s) const { return transition_.at(now_s); }
  bool haveDome() const { return !transition_.empty(); }
  std::size_t domeSize() const { return transition_.target().size(); }

  // report.json: lights, hdr, white_border, clipped_lights_now, state,
  // state_at_end, and camera.exposure_at_last_fit / exposure_locks.
  void writeReport(nlohmann::json& report) const;

 private:
  // The fit frame and what a fit has beyond the 8-bit maps.
  struct FitFrame {
    const ibl::MirrorBallView* view = nullptr;  // null: its tag was not found
    ibl::RgbPixelReader read_pixel;
    std::optional<ibl::CubeMapRGB> hdr;  // a merged bracket
    ManualExposure exposure{0.0, 0.0};   // the unit of the camera-linear values (0: the source cannot say)
    FrameResponse response;              // the same with the white balance
    bool exposure_locked = false;
  };
  // A bracket's frames, kept for the merge.
  struct BracketFrames {
    ImageRGB8 reference;
    ibl::MirrorBallView view;
    ibl::ProbeOutline outline;
    bool exposure_locked = false;
    std::vector<BracketCandidate> frames;
    std::chrono::steady_clock::time_point started;
    double own_s = 0.0;  // probelight's own work on the bracket's frames (the rest of the wall time is the camera's)
    double reference_time_s = NAN;  // the reference frame's time (FrameContext::time_s)
    FrameResponse response;         // the reference frame's
  };

  bool startBracket(const FrameContext& ctx);
  Status finishBracket(std::uint64_t frame_number, MapsStage& maps);
  Status fitLights(std::uint64_t frame_number, const FitFrame& fit_frame, MapsStage& maps);
  void reportWhiteBorder(const ibl::LightingFit& fit);
  void saveLighting(const ibl::LightingFit& fit, MapsStage& maps);
  Status followClippedLights(std::uint64_t frame_number, const MapsStage& maps);
  // shown_lighting_ from lighting_ and the maps' response now.
  void showInMapsUnits(const MapsStage& maps);
  Status checkLightChange(std::uint64_t frame_number, const MapsStage& maps);
  void syncExposureLock(std::uint64_t frames_since_camera_start);
  void showStoredLighting(double now_s);
  double clipLevel() const;
  bool ballClips(const ImageRGB8& rgb, const ibl::ProbeOutline& outline) const;
  void warn(const std::string& message) const;
  void info(const std::string& message) const;

  const PipelineSettings& settings_;
  RigGeometry rig_;
  CameraIntrinsics camera_;
  ExposureControl& camera_control_;
  RunReport& report_;
  std::ostream& log_;

  LightingStateMachine machine_;
  BracketController bracket_;
  std::optional<BracketFrames> bracket_frames_;
  std::chrono::steady_clock::time_point admitted_;  // when admit() took the frame being kept
  bool bracket_over_ = false;  // ... and whether it ended the bracket
  std::unique_ptr<tracking::TagTracker> bracket_tracker_;  // follows the tag through each bracket's frames
  LightTransition transition_;
  ClippedLightFollower clipped_;
  ibl::SceneLighting lighting_;  // no highlight until the first calibration; in the fit frame's units
  ibl::SceneLighting shown_lighting_;  // lighting_ in the maps' units
  FrameResponse fit_response_;  // the camera's response in the fit frame (0s: unknown)
  // The maps' response when lights_fitted_e_up_ was read from them.
  FrameResponse e_up_response_;
  std::optional<glm::dvec3> room_e_up_maps_;  // roomGroundIrradiance()
  std::optional<StoredLighting> stored_lighting_;
  double frame_time_s_ = 0.0;  // of the last frame the pipeline ran on
  glm::dvec3 lights_fitted_e_up_{0.0};  // the ground's irradiance when the lights were last fitted
  bool exposure_locked_ = false;
  bool said_no_exposure_control_ = false;

  nlohmann::json lights_report_, hdr_report_, white_border_report_, clipped_now_report_, state_report_;
  nlohmann::json exposure_at_last_fit_;  // null until a fit
};

}  // namespace probelight
