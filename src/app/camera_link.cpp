#include "app/camera_link.hpp"

#include <algorithm>
#include <iomanip>
#include <ostream>

#include "core/log_priority.hpp"
#include "core/monotonic_clock.hpp"

namespace probelight {

namespace {

constexpr std::chrono::milliseconds kFrameWait{2000};

}  // namespace

CameraLink::CameraLink(FrameSource& source, double reconnect_max_interval_s, bool can_reconnect, RunReport& report,
                       std::ostream& log)
    : source_(source),
      can_reconnect_(can_reconnect),
      report_(report),
      log_(log),
      backoff_(0.5, reconnect_max_interval_s) {}

CameraEvent CameraLink::next(FrameLease& lease) {
  const FrameWait wait = source_.waitFrame(kFrameWait, lease);
  if (wait == FrameWait::kTimeout) {
    // A camera that stops delivering: keep the last picture, say so, and
    // after a long silence treat it as gone (re-open it).
    log_ << logPrefix(LogPriority::kWarning) << "probelight: no frame from " << source_.name() << " for 2 s\n";
    if (++consecutive_timeouts_ >= kTimeoutsBeforeReconnect && can_reconnect_) {
      consecutive_timeouts_ = 0;
      onLost("no frame for " + std::to_string(2 * kTimeoutsBeforeReconnect) + " s");
      return CameraEvent::kLost;
    }
    if (consecutive_timeouts_ >= kTimeoutsBeforeGivingUp) {
      log_ << logPrefix(LogPriority::kError) << "probelight: giving up: " << source_.name()
           << " delivered nothing for 30 s\n";
      return CameraEvent::kEnded;
    }
    return CameraEvent::kNoFrame;
  }
  if (wait == FrameWait::kEndOfStream) return CameraEvent::kEnded;
  if (wait == FrameWait::kError) {
    if (can_reconnect_) {
      onLost(source_.lastError());
      return CameraEvent::kLost;
    }
    return CameraEvent::kFailed;
  }
  consecutive_timeouts_ = 0;
  ++frames_since_start_;
  // Exposure time and gain of every frame: the ball's brightness follows them.
  if (lease->metadata.exposure_us > 0.0) exposure_us_.add(lease->metadata.exposure_us);
  if (lease->metadata.analogue_gain > 0.0) analogue_gain_.add(lease->metadata.analogue_gain);
  return CameraEvent::kFrame;
}

void CameraLink::onLost(const std::string& why) {
  report_.count("camera_losses");
  last_problem_ = why;
  log_ << logPrefix(LogPriority::kError) << "probelight: " << source_.name() << ": " << why
       << "; keeping the last frame and reconnecting\n";
  source_.stop();
  backoff_.onLost(monotonicNowS());
}

bool CameraLink::tryReconnect(std::string& status) {
  const double now_s = monotonicNowS();
  if (backoff_.due(now_s)) {
    std::string error;
    if (source_.start(error)) {
      report_.count("camera_reconnects");
      log_ << logPrefix(LogPriority::kInfo) << "probelight: " << source_.name() << " is back after "
           << backoff_.failedAttempts() + 1 << " attempt(s), " << std::fixed << std::setprecision(1)
           << now_s - backoff_.lostSinceS() << " s\n";
      backoff_.onReconnected();
      frames_since_start_ = 0;
      return true;
    }
    report_.count("camera_reconnect_failures");
    last_problem_ = error;
    backoff_.onAttemptFailed(now_s);
    log_ << logPrefix(LogPriority::kWarning) << "probelight: reconnect failed: " << error << "; next attempt in "
         << std::fixed << std::setprecision(1) << backoff_.nextAttemptS() - now_s << " s\n";
  }
  const double wait_s = std::max(0.0, backoff_.nextAttemptS() - monotonicNowS());
  status = "Camera lost: reconnecting" +
           (wait_s > 0.95 ? " in " + std::to_string(static_cast<int>(wait_s + 0.5)) + " s" : std::string());
  return false;
}

int CameraLink::silentSeconds() const {
  return static_cast<int>(consecutive_timeouts_ * std::chrono::duration_cast<std::chrono::seconds>(kFrameWait).count());
}

std::chrono::milliseconds CameraLink::idleWait() const {
  const double wait_s = std::max(0.0, backoff_.nextAttemptS() - monotonicNowS());
  return std::chrono::milliseconds(static_cast<int>(1000.0 * std::min(0.2, wait_s)) + 1);
}

void CameraLink::writeReport(nlohmann::json& camera_section) const {
  camera_section["stream"] = source_.streamDescription();
  camera_section["losses"] = report_.counter("camera_losses");
  camera_section["reconnects"] = report_.counter("camera_reconnects");
  camera_section["reconnect_failures"] = report_.counter("camera_reconnect_failures");
  if (!last_problem_.empty()) camera_section["last_problem"] = last_problem_;
  recordSeries(camera_section, "exposure_us", exposure_us_);
  recordSeries(camera_section, "analogue_gain", analogue_gain_);
}

}  // namespace probelight
