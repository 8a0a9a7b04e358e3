// Seconds on the monotonic clock, for the pure units that take times as
// numbers (reconnect back-off, the status LED's blinking).
#pragma once

#include <chrono>

namespace probelight {

inline double monotonicNowS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace probelight
