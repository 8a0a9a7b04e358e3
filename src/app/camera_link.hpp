// The camera as the kiosk's loop sees it: frames, and a camera that stops
// delivering or goes away and comes back. It waits for frames, treats a long
// silence or an error as a lost camera, and re-opens it on a back-off
// schedule (reconnect_backoff.hpp). It knows nothing of the frames'
// contents; it records their exposure metadata and the camera's problems
// for report.json's `camera` section.
#pragma once

#include <chrono>
#include <cstdint>
#include <iosfwd>
#include <string>

#include <nlohmann/json.hpp>

#include "app/reconnect_backoff.hpp"
#include "capture/frame_source.hpp"
#include "stages/run_report.hpp"

namespace probelight {

enum class CameraEvent {
  kFrame,    // a frame is in the lease
  kNoFrame,  // none yet (a timeout, said): ask again
  kLost,     // the camera just went away: it is being reconnected
  kEnded,    // the stream ended, or the camera is gone for good: stop
  kFailed,   // a source that cannot reconnect failed (a folder with no decodable image): stop, exit 2
};

class CameraLink {
 public:
  // `can_reconnect`: cameras come back; a folder of images that failed does not.
  CameraLink(FrameSource& source, double reconnect_max_interval_s, bool can_reconnect, RunReport& report,
             std::ostream& log);

  CameraEvent next(FrameLease& lease);
  bool lost() const { return backoff_.lost(); }
  // While lost: re-opens the camera when an attempt is due. True once it is
  // back; otherwise `status` says what the screen should (with the wait).
  bool tryReconnect(std::string& status);
  // How long the loop may sleep before the next attempt (a few redraws a
  // second are plenty for a still picture).
  std::chrono::milliseconds idleWait() const;
  // While the camera is silent (next() said kNoFrame): for how long, in
  // whole waits (0 once a frame came).
  int silentSeconds() const;
  // Frames since the camera (re)started, the last one included.
  std::uint64_t framesSinceStart() const { return frames_since_start_; }

  // report.json: camera.losses, reconnects, reconnect_failures,
  // last_problem, and the frames' exposure_us and analogue_gain.
  void writeReport(nlohmann::json& camera_section) const;

 private:
  void onLost(const std::string& why);

  // A camera silent for this many 2 s waits is re-opened.
  static constexpr int kTimeoutsBeforeReconnect = 5;
  static constexpr int kTimeoutsBeforeGivingUp = 15;

  FrameSource& source_;
  bool can_reconnect_;
  RunReport& report_;
  std::ostream& log_;
  ReconnectBackoff backoff_;
  int consecutive_timeouts_ = 0;
  std::uint64_t frames_since_start_ = 0;
  std::string last_problem_;
  SampleSeries exposure_us_, analogue_gain_;
};

}  // namespace probelight
