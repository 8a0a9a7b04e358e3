// Whether a source sets its camera's focus, and where (issue 48). A moving
// lens (the Camera Module 3's) changes the focal length and distortion as it
// focuses, so camera.yaml's intrinsics hold at the lens position they were
// calibrated at alone: where the file names one and the camera can drive its
// lens, the source holds it there (autofocus off). A camera that cannot (a
// fixed-focus module, vimc) is not refused: a lens that never moves keeps its
// calibration, and a lens focused by hand is the user's to set; it is said
// once, as a warning. Pure: the camera's controls are passed in, so the
// choice is tested without one (the libcamera source and the simulated
// camera both take it from here).
#pragma once

#include <optional>
#include <string>

namespace probelight {

// What a camera offers for its lens, as its controls say.
struct LensControlsOffered {
  bool lens_position = false;  // LensPosition: the lens can be driven to a position
  bool af_mode = false;        // AfMode: an autofocus, to be switched to manual first
  // LensPosition's range (dioptres), where the camera reports one.
  std::optional<double> min_dioptres;
  std::optional<double> max_dioptres;
};

// The focus controls a source sends when it starts.
struct FocusRequest {
  // Where to drive the lens; nullopt: send no focus control at all (the
  // camera's own focus behaviour, as before camera.yaml could name one).
  std::optional<double> lens_position_dioptres;
  bool af_mode_manual = false;  // send AfMode = manual with it
  // One line where camera.yaml's position cannot be had as written; empty
  // otherwise.
  std::string warning;
};

// `calibrated_dioptres`: camera.yaml's lens_position_dioptres. Outside the
// range the camera reports, the position is clamped into it (as the camera
// would clamp it) and the warning says so.
FocusRequest chooseFocusRequest(std::optional<double> calibrated_dioptres, const LensControlsOffered& offered,
                                const std::string& camera_name);

}  // namespace probelight
