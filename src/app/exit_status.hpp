// The one place a command's Status becomes the process's exit status, its
// message one line on stderr: 0 ok, 1 a runtime failure, 2 bad flags, files
// or configuration, 3 (analyze, render) the tag or the ball not found.
#pragma once

#include <iosfwd>
#include <string>

#include "core/status.hpp"

namespace probelight {

inline constexpr int kAnalyzeNotFoundExitStatus = 3;

int exitStatusOf(const Status& status);

// Says what failed ("probelight: <command>: <message>", the command left out
// for `run`) and returns exitStatusOf(status).
int finishCommand(const Status& status, const std::string& command, std::ostream& log);

}  // namespace probelight
