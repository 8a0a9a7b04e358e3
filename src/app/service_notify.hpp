// Telling systemd how the kiosk is doing (sd_notify): READY=1 once the first
// frame is on the screen (the unit is Type=notify), WATCHDOG=1 from the
// render loop (a hung GPU or camera stops the pings and systemd restarts the
// service), STATUS= lines for `systemctl status`. Outside systemd
// (NOTIFY_SOCKET unset) every call does nothing.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace probelight {

class ServiceNotifier {
 public:
  ServiceNotifier();
  // After the first frame is shown. Once.
  void ready(const std::string& status);
  // From the render loop, every frame: sends at most twice per watchdog
  // period (WATCHDOG_USEC), as sd_watchdog_enabled advises.
  void frameShown();
  void status(const std::string& text);
  void stopping();
  bool watchdogEnabled() const { return watchdog_interval_us_ > 0; }

 private:
  bool ready_sent_ = false;
  std::uint64_t watchdog_interval_us_ = 0;
  std::chrono::steady_clock::time_point last_ping_{};
};

}  // namespace probelight
