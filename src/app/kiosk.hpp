// `probelight run`: frames in, composited frames out, lighting recalibrated on
// demand. Returns the process exit status (0 ok, 1 runtime failure, 2 bad
// flags or configuration).
#pragma once

#include <iosfwd>

#include "app/command_line.hpp"

namespace probelight {

int runKiosk(const RunOptions& options, std::ostream& log);

}  // namespace probelight
