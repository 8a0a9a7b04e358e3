// When to try re-opening a camera that went away: soon at first (a loose
// cable re-seated), then exponentially less often, so a camera that is gone
// for good does not keep the board busy re-enumerating. Pure: times are
// passed in (seconds on a monotonic clock), so it is tested without waiting.
#pragma once

namespace probelight {

class ReconnectBackoff {
 public:
  ReconnectBackoff(double first_interval_s = 0.5, double max_interval_s = 30.0);

  // The camera was lost at `now_s`: the first attempt is due one first
  // interval later.
  void onLost(double now_s);
  bool lost() const { return lost_; }
  bool due(double now_s) const { return lost_ && now_s >= next_attempt_s_; }
  // An attempt at `now_s` failed: the next waits twice as long as the last
  // wait, up to the maximum.
  void onAttemptFailed(double now_s);
  // The camera is back: the schedule starts over at the next loss.
  void onReconnected();

  int failedAttempts() const { return failed_attempts_; }
  double nextAttemptS() const { return next_attempt_s_; }
  double lostSinceS() const { return lost_since_s_; }

 private:
  double first_interval_s_;
  double max_interval_s_;
  bool lost_ = false;
  double lost_since_s_ = 0.0;
  double interval_s_ = 0.0;
  double next_attempt_s_ = 0.0;
  int failed_attempts_ = 0;
};

}  // namespace probelight
