// A camera that disappears on a schedule, around any source, for long runs
// that must show a loss costs nothing (scripts/soak.sh on replayed frames):
// after every `every_frames` frames delivered, the next wait fails as a
// lost camera's does, and the next `failed_restarts` start() calls fail
// before one restarts the source underneath. probelight.yaml's
// faults.camera_loss_every_frames and faults.camera_loss_failed_restarts.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "capture/frame_source.hpp"

namespace probelight {

class ScheduledCameraLoss : public FrameSource {
 public:
  // every_frames >= 1.
  ScheduledCameraLoss(std::unique_ptr<FrameSource> inner, std::uint64_t every_frames, int failed_restarts);

  bool start(std::string& error) override;
  void stop() override { inner_->stop(); }
  FrameWait waitFrame(std::chrono::milliseconds timeout, FrameLease& lease) override;
  std::string lastError() const override { return lost_ ? lost_reason_ : inner_->lastError(); }
  std::string name() const override { return inner_->name(); }
  bool lockExposure(bool locked) override { return inner_->lockExposure(locked); }
  bool setExposureLadder(const std::vector<ManualExposure>& per_frame) override {
    return inner_->setExposureLadder(per_frame);
  }
  std::optional<double> shortestExposureUs() const override { return inner_->shortestExposureUs(); }
  bool takesExposureLadders() const override { return inner_->takesExposureLadders(); }
  std::string focusWarning() const override { return inner_->focusWarning(); }

  std::uint64_t lossesInjected() const { return losses_; }

 private:
  std::unique_ptr<FrameSource> inner_;
  std::uint64_t every_frames_;
  int failed_restarts_;
  std::uint64_t delivered_since_start_ = 0;
  std::uint64_t losses_ = 0;
  int restarts_failed_ = 0;
  bool lost_ = false;
  std::string lost_reason_;
};

}  // namespace probelight
