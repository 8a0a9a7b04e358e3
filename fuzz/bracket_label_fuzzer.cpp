// --bracket FILE@EV, the label of one bracket frame: the file and a finite
// EV within 0.125..24 stops; or a recorded frame's file alone (its EV from
// its metadata, later); or one UsageError line.
#include <algorithm>

#include "app/command_line.hpp"
#include "capture/frame_recording.hpp"
#include "fuzz/fuzz_input.hpp"

using namespace probelight;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // As argv would hold it: up to the first NUL.
  std::string label(reinterpret_cast<const char*>(data), size);
  label.resize(std::min(label.size(), label.find('\0')));
  try {
    const AnalyzeOptions options = parseAnalyzeOptions(
        {"--frame", "frame.png", "--calibration", "camera.yaml", "--rig", "rig.yaml", "--out", "out", "--bracket", label});
    fuzz::require(options.brackets.size() == 1, "one --bracket did not give one bracket frame");
    const BracketOption& bracket = options.brackets[0];
    if (bracket.ev_from_metadata) {
      fuzz::require(bracket.path == label && label.find('@') == std::string::npos && isRecordedFramePath(label),
                    "a label without @EV taken for a recorded frame that is not one");
      return 0;
    }
    fuzz::require(fuzz::finite(bracket.ev) && std::abs(bracket.ev) >= kMinBracketEv && std::abs(bracket.ev) <= kMaxBracketEv,
                  "a bracket EV out of 0.125..24 stops accepted");
    fuzz::require(!bracket.path.empty() && label.compare(0, bracket.path.size(), bracket.path) == 0 &&
                      label[bracket.path.size()] == '@',
                  "the bracket's file is not the label up to its last '@'");
  } catch (const UsageError& error) {
    const std::string message = error.what();
    fuzz::require(!message.empty() && message.find('\n') == std::string::npos, "a usage error of more than one line");
  }
  return 0;
}
