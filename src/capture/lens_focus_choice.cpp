#include "capture/lens_focus_choice.hpp"

#include <algorithm>
#include <sstream>

namespace probelight {

namespace {

// Six significant digits: "2.5", "32"; dioptres past that are noise.
std::string dioptresText(double dioptres) {
  std::ostringstream text;
  text << dioptres;
  return text.str();
}

}  // namespace

FocusRequest chooseFocusRequest(std::optional<double> calibrated_dioptres, const LensControlsOffered& offered,
                                const std::string& camera_name) {
  FocusRequest request;
  if (!calibrated_dioptres) return request;
  const std::string asked = "camera.yaml's lens_position_dioptres " + dioptresText(*calibrated_dioptres);
  if (!offered.lens_position) {
    request.warning = "camera: " + camera_name + " has no lens control (LensPosition), so " + asked +
                      " is not set: right for a fixed-focus lens, which cannot move off its calibration";
    return request;
  }
  double position = *calibrated_dioptres;
  if (offered.min_dioptres && offered.max_dioptres && *offered.min_dioptres <= *offered.max_dioptres) {
    position = std::clamp(position, *offered.min_dioptres, *offered.max_dioptres);
    if (position != *calibrated_dioptres)
      request.warning = "camera: " + camera_name + "'s lens reaches " + dioptresText(*offered.min_dioptres) +
                        " to " + dioptresText(*offered.max_dioptres) + " dioptres, so " + asked +
                        " is set as " + dioptresText(position) +
                        ": the intrinsics may not hold (was camera.yaml calibrated with another camera?)";
  }
  request.lens_position_dioptres = position;
  request.af_mode_manual = offered.af_mode;
  return request;
}

}  // namespace probelight
