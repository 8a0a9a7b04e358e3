// A failure as a value: what went wrong, in one line a user can act on, and
// what kind of failure it is. The pipeline's stages and the commands return
// it; one place (app/exit_status.hpp) turns it into the process's exit
// status.
#pragma once

#include <string>
#include <utility>

namespace probelight {

class [[nodiscard]] Status {
 public:
  enum class Kind {
    kOk,
    kRuntimeFailure,  // the GPU, the camera, a file that could not be written
    kBadInput,        // a flag, a file or a frame the user gave
    kNotFound,        // analyze, render: the tag or the ball is not in the frame
  };

  Status() = default;
  static Status ok() { return {}; }
  static Status runtimeFailure(std::string message) { return Status(Kind::kRuntimeFailure, std::move(message)); }
  static Status badInput(std::string message) { return Status(Kind::kBadInput, std::move(message)); }
  static Status notFound(std::string message) { return Status(Kind::kNotFound, std::move(message)); }

  bool isOk() const { return kind_ == Kind::kOk; }
  Kind kind() const { return kind_; }
  const std::string& message() const { return message_; }

 private:
  Status(Kind kind, std::string message) : kind_(kind), message_(std::move(message)) {}
  Kind kind_ = Kind::kOk;
  std::string message_;
};

}  // namespace probelight

// Returns from the enclosing function when `expression` (a Status) failed.
#define PROBELIGHT_TRY(expression)                                  \
  do {                                                              \
    if (::probelight::Status status_ = (expression); !status_.isOk()) \
      return status_;                                               \
  } while (false)
