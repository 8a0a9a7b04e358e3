// The camera's exposure, as the pipeline asks for it: a lock while the lights
// are fitted, and a ladder of fixed exposures for an exposure bracket. A
// FrameSource is one; the bracket controller (stages/bracket_controller.hpp)
// is driven through this alone, so that its tests can stand in a camera of
// their own.
#pragma once

#include <optional>
#include <vector>

namespace probelight {

class ExposureControl {
 public:
  virtual ~ExposureControl() = default;

  struct ManualExposure {
    double exposure_us = 0.0;
    double analogue_gain = 1.0;
  };

  // Freezes (true) or releases (false) auto exposure and white balance, so
  // that frames taken for a recalibration see the ball the same way. Returns
  // false when the source has no such controls.
  virtual bool lockExposure(bool locked) {
    (void)locked;
    return false;
  }
  // Fixed exposures (auto exposure off) for the frames that follow, one
  // frame each, in order, as an exposure bracket needs; the last holds until
  // the next call. A camera takes controls with each request, so a ladder
  // asked at once arrives on consecutive frames after the pipeline's latency
  // (a few frames), paid once. A new call replaces the exposures not yet
  // begun; an empty one goes back to what lockExposure set. Frames already in
  // flight keep their exposure: each frame's metadata (exposure_us,
  // analogue_gain) says what it got, and a sensor may clamp the request.
  // While a ladder is asked for, a source hands over every frame in order
  // (not only the newest), so that no rung is lost. Returns false when the
  // source has no such control.
  virtual bool setExposureLadder(const std::vector<ManualExposure>& per_frame) {
    (void)per_frame;
    return false;
  }
  // The sensor's shortest exposure time (microseconds), where the source
  // knows it: a ladder's rungs below it would all be taken at it.
  virtual std::optional<double> shortestExposureUs() const { return std::nullopt; }
  // Whether setExposureLadder takes a ladder (once started): what a
  // recording says of its camera, so that its replay does the same.
  virtual bool takesExposureLadders() const { return false; }
};

}  // namespace probelight
