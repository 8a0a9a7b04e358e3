#include "app/exit_status.hpp"

#include <ostream>

#include "core/log_priority.hpp"

namespace probelight {

int exitStatusOf(const Status& status) {
  switch (status.kind()) {
    case Status::Kind::kOk: return 0;
    case Status::Kind::kRuntimeFailure: return 1;
    case Status::Kind::kBadInput: return 2;
    case Status::Kind::kNotFound: return kAnalyzeNotFoundExitStatus;
  }
  return 1;
}

int finishCommand(const Status& status, const std::string& command, std::ostream& log) {
  if (!status.isOk())
    log << logPrefix(LogPriority::kError) << "probelight: " << (command.empty() ? "" : command + ": ")
        << status.message() << "\n";
  return exitStatusOf(status);
}

}  // namespace probelight
