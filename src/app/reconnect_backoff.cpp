#include "app/reconnect_backoff.hpp"

#include <algorithm>

namespace probelight {

ReconnectBackoff::ReconnectBackoff(double first_interval_s, double max_interval_s)
    : first_interval_s_(first_interval_s), max_interval_s_(std::max(first_interval_s, max_interval_s)) {}

void ReconnectBackoff::onLost(double now_s) {
  if (lost_) return;  // already counting from the first loss
  lost_ = true;
  lost_since_s_ = now_s;
  interval_s_ = first_interval_s_;
  next_attempt_s_ = now_s + interval_s_;
  failed_attempts_ = 0;
}

void ReconnectBackoff::onAttemptFailed(double now_s) {
  ++failed_attempts_;
  interval_s_ = std::min(2.0 * interval_s_, max_interval_s_);
  next_attempt_s_ = now_s + interval_s_;
}

void ReconnectBackoff::onReconnected() {
  lost_ = false;
  failed_attempts_ = 0;
}

}  // namespace probelight
