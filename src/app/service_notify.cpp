#include "app/service_notify.hpp"

#include <systemd/sd-daemon.h>

namespace probelight {

ServiceNotifier::ServiceNotifier() {
  std::uint64_t usec = 0;
  if (sd_watchdog_enabled(0, &usec) > 0) watchdog_interval_us_ = usec;
}

void ServiceNotifier::ready(const std::string& status) {
  if (ready_sent_) return;
  ready_sent_ = true;
  sd_notify(0, ("READY=1\nSTATUS=" + status).c_str());
}

void ServiceNotifier::frameShown() {
  if (watchdog_interval_us_ == 0) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_ping_ < std::chrono::microseconds(watchdog_interval_us_ / 2)) return;
  last_ping_ = now;
  sd_notify(0, "WATCHDOG=1");
}

void ServiceNotifier::status(const std::string& text) { sd_notify(0, ("STATUS=" + text).c_str()); }

void ServiceNotifier::stopping() { sd_notify(0, "STOPPING=1"); }

}  // namespace probelight
