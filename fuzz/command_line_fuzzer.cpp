// The command line: `probelight run | analyze | render | calibrate-camera`
// with any arguments (the input's NUL-separated strings; its first byte
// picks the command) parses, or gives one UsageError line, or help.
#include <vector>

#include "app/command_line.hpp"
#include "fuzz/fuzz_input.hpp"

using namespace probelight;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  std::vector<std::string> args(1);
  for (std::size_t i = 1; i < size; ++i) {
    if (data[i] == 0) {
      args.emplace_back();
    } else {
      args.back() += static_cast<char>(data[i]);
    }
  }
  try {
    switch (data[0] % 4) {
      case 0: {
        const RunOptions run = parseRunOptions(args);
        fuzz::require(run.frames >= 0, "a negative --frames accepted");
        break;
      }
      case 1: {
        const AnalyzeOptions analyze = parseAnalyzeOptions(args);
        fuzz::require(analyze.brackets.size() <= kMaxBracketFrames, "more than 16 --bracket frames accepted");
        for (const BracketOption& bracket : analyze.brackets)
          fuzz::require(std::abs(bracket.ev) >= kMinBracketEv && std::abs(bracket.ev) <= kMaxBracketEv,
                        "a bracket EV out of 0.125..24 stops accepted");
        break;
      }
      case 2:
        parseRenderOptions(args);
        break;
      default:
        parseCalibrateCameraOptions(args);
        break;
    }
  } catch (const UsageError& error) {
    const std::string message = error.what();
    fuzz::require(!message.empty() && message.find('\n') == std::string::npos, "a usage error of more than one line");
  } catch (const HelpRequested&) {
  }
  return 0;
}
