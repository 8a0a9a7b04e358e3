// `probelight run`: frames in, composited frames out, lighting recalibrated on
// demand. A failure comes back as a Status (a runtime failure, or bad flags,
// files or configuration); main() turns it into the exit status.
#pragma once

#include <iosfwd>

#include "app/command_line.hpp"
#include "core/status.hpp"

namespace probelight {

Status runKiosk(const RunOptions& options, std::ostream& log);

}  // namespace probelight
