// Which exposure controls the camera's next request must carry: a pure
// state machine between what the kiosk wants (auto exposure, a lock while
// the lights are fitted, a fixed exposure for each frame of a bracket) and
// what the pipeline already has (libcamera's controls persist once sent, so
// each is sent once, on a change). Kept apart from libcamera so that it is
// tested here with synthetic events.
#pragma once

#include <deque>
#include <optional>
#include <vector>

namespace probelight {

struct ExposureSetting {
  double exposure_us = 0.0;
  double analogue_gain = 1.0;
  bool operator==(const ExposureSetting& other) const {
    return exposure_us == other.exposure_us && analogue_gain == other.analogue_gain;
  }
};

struct ExposureControls {
  enum class Kind {
    kNone,    // nothing new: the pipeline has what is wanted
    kAuto,    // AE and AWB on
    kLocked,  // AE and AWB off, keeping the values they last chose
    kManual,  // AE and AWB off, at `setting`
  };
  Kind kind = Kind::kNone;
  ExposureSetting setting;
};

class ExposureSequencer {
 public:
  void setLocked(bool locked) { locked_ = locked; }
  // A bracket's exposures, one request each, in order; the last is held.
  // libcamera takes controls with each request, so a whole ladder asked at
  // once reaches the sensor on consecutive frames and costs the pipeline's
  // latency (the requests queued ahead, the sensor's own delay) once, not
  // once a rung. A new ladder replaces the rungs not yet sent. Empty ends
  // the bracket: rungs not yet sent are dropped, and the way back is the
  // exposure the frames had before it, sent as a manual value first (so
  // that AE does not restart from the short one, and a lock keeps exactly
  // what it had), then the lock state's own controls.
  void setManual(const std::vector<ExposureSetting>& ladder);
  // From a ladder until it ends. A bracket's rungs are one frame each: the
  // source must hand over every frame in order then, not only the newest.
  bool inBracket() const { return in_bracket_; }
  // Each delivered frame's metadata: what to come back to after a bracket.
  void onFrame(const ExposureSetting& used);
  // What the next request must carry, and now counts as sent.
  ExposureControls nextRequest();
  // A new pipeline (the camera restarted): it has nothing yet.
  void pipelineRestarted() { applied_kind_ = ExposureControls::Kind::kNone; }

 private:
  bool locked_ = false;
  bool in_bracket_ = false;
  std::deque<ExposureSetting> pending_;       // the ladder's rungs not yet sent
  ExposureSetting held_;                      // the bracket's newest rung sent
  std::optional<ExposureSetting> last_seen_;  // newest frame's
  std::optional<ExposureSetting> return_to_;  // set when a bracket ends
  bool restored_ = false;                     // return_to_ went out; the lock state is next
  // What the pipeline has.
  ExposureControls::Kind applied_kind_ = ExposureControls::Kind::kNone;
  ExposureSetting applied_setting_;
};

}  // namespace probelight
