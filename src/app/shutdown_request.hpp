// SIGTERM (systemd stopping the service) and SIGINT (Ctrl-C) end the kiosk
// between frames instead of killing it mid-frame: the report is written,
// systemd hears STOPPING=1, the camera is stopped through libcamera, the
// status LED goes dark and the screen is handed back.
#pragma once

namespace probelight {

// Installs the handlers (idempotent). The handler only records the signal.
void installShutdownHandlers();
// The signal that asked for the end (SIGTERM, SIGINT), or 0.
int shutdownSignal();
// For tests: forget a recorded signal.
void clearShutdownRequest();

}  // namespace probelight
