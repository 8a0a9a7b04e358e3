#include "capture/scheduled_camera_loss.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace probelight {

ScheduledCameraLoss::ScheduledCameraLoss(std::unique_ptr<FrameSource> inner, std::uint64_t every_frames,
                                         int failed_restarts)
    : inner_(std::move(inner)), every_frames_(every_frames), failed_restarts_(std::max(0, failed_restarts)) {
  if (!inner_ || every_frames_ == 0) throw std::invalid_argument("ScheduledCameraLoss: a source and every_frames >= 1");
}

bool ScheduledCameraLoss::start(std::string& error) {
  if (lost_ && restarts_failed_ < failed_restarts_) {
    ++restarts_failed_;
    error = "camera still gone (injected by faults.camera_loss_failed_restarts, attempt " +
            std::to_string(restarts_failed_) + " of " + std::to_string(failed_restarts_) + " to fail)";
    return false;
  }
  if (!inner_->start(error)) return false;
  lost_ = false;
  restarts_failed_ = 0;
  delivered_since_start_ = 0;
  return true;
}

FrameWait ScheduledCameraLoss::waitFrame(std::chrono::milliseconds timeout, FrameLease& lease) {
  if (lost_) return FrameWait::kError;
  if (delivered_since_start_ == every_frames_) {
    lost_ = true;
    ++losses_;
    lost_reason_ = "camera disconnected (injected by faults.camera_loss_every_frames after " +
                   std::to_string(every_frames_) + " frames)";
    return FrameWait::kError;
  }
  const FrameWait wait = inner_->waitFrame(timeout, lease);
  if (wait == FrameWait::kFrame) ++delivered_since_start_;
  return wait;
}

}  // namespace probelight
