#include "capture/exposure_sequencer.hpp"

namespace probelight {

void ExposureSequencer::setManual(const std::vector<ExposureSetting>& ladder) {
  if (!ladder.empty()) {
    // Entering (or moving within) a bracket. The exposure to come back to
    // is the last one seen before the bracket began.
    if (!in_bracket_ && !return_to_) return_to_ = last_seen_;
    in_bracket_ = true;
    pending_.assign(ladder.begin(), ladder.end());
    restored_ = false;
    return;
  }
  if (!in_bracket_) return;
  in_bracket_ = false;
  pending_.clear();
  restored_ = !return_to_;  // nothing known to restore: straight to the lock state
}

void ExposureSequencer::onFrame(const ExposureSetting& used) {
  if (used.exposure_us > 0.0) last_seen_ = used;
}

ExposureControls ExposureSequencer::nextRequest() {
  using Kind = ExposureControls::Kind;
  auto send = [&](Kind kind, const ExposureSetting& setting = {}) {
    applied_kind_ = kind;
    applied_setting_ = setting;
    return ExposureControls{kind, setting};
  };
  if (in_bracket_) {
    if (!pending_.empty()) {
      held_ = pending_.front();
      pending_.pop_front();
    }
    if (applied_kind_ == Kind::kManual && applied_setting_ == held_) return {};
    return send(Kind::kManual, held_);
  }
  if (return_to_ && !restored_) {
    restored_ = true;
    return send(Kind::kManual, *return_to_);
  }
  if (return_to_) {
    // The pre-bracket exposure is in the pipeline: as a lock it is exactly
    // what the lock had, so only auto needs sending.
    return_to_.reset();
    if (locked_) {
      applied_kind_ = Kind::kLocked;
      return {};
    }
    return send(Kind::kAuto);
  }
  const Kind wanted = locked_ ? Kind::kLocked : Kind::kAuto;
  if (applied_kind_ == wanted) return {};
  // A manual value left in the pipeline (a bracket with nothing to restore)
  // counts as locked only when asked to lock: send kLocked to make it so.
  return send(wanted);
}

}  // namespace probelight
