// probelight's entry point: dispatches the command and maps failures to exit
// statuses (2: bad flags or configuration, 1: runtime failure, 3: analyze
// found no tag or no ball).
#include <cstdlib>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/analyze.hpp"
#include "app/calibrate_camera.hpp"
#include "app/list_cameras.hpp"
#include "app/print_tag.hpp"
#include "app/command_line.hpp"
#include "app/exit_status.hpp"
#include "app/kiosk.hpp"
#include "core/log_priority.hpp"
#include "sim/scene_config.hpp"

#include <opencv2/core/utils/logger.hpp>

int main(int argc, char** argv) {
  using namespace probelight;
  // OpenCV's decoders log their own errors on stderr ("[ERROR:0@0.07] ...
  // OpenJPEG2000: Malformed JP2"), a second line beside the one that names
  // the file and says what failed. OPENCV_LOG_LEVEL still turns them on.
  if (!std::getenv("OPENCV_LOG_LEVEL")) cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    std::cout << usageText();
    return args.empty() ? 2 : 0;
  }
  if (args[0] == "--version") {
    std::cout << "probelight 0.1.0\n";
    return 0;
  }
  const std::string command = args[0];
  args.erase(args.begin());
  // Under systemd, stderr is the journal: every line gets its priority.
  std::unique_ptr<JournalPrefixes> journal;
  if (stderrIsJournal()) journal = std::make_unique<JournalPrefixes>(std::cerr);
  try {
    // The simulator's thread count from the environment, checked before any
    // scene is made (it is a default member of every SceneConfig).
    try {
      (void)sim::defaultRenderThreads();
    } catch (const std::invalid_argument& error) {
      throw UsageError(error.what());
    }
    // Flags that still work but are going: said once, before the command runs.
    auto warn = [](const std::vector<std::string>& warnings) {
      for (const std::string& warning : warnings)
        std::cerr << logPrefix(LogPriority::kWarning) << "probelight: " << warning << "\n";
    };
    if (command == "run") {
      const RunOptions options = parseRunOptions(args);
      warn(options.warnings);
      return finishCommand(runKiosk(options, std::cerr), "", std::cerr);
    }
    if (command == "analyze") {
      const AnalyzeOptions options = parseAnalyzeOptions(args);
      warn(options.warnings);
      return finishCommand(runAnalyze(options, std::cerr), command, std::cerr);
    }
    if (command == "render") {
      const RenderOptions options = parseRenderOptions(args);
      warn(options.frame.warnings);
      return finishCommand(runRender(options, std::cerr), command, std::cerr);
    }
    if (command == "cameras") return runListCameras(parseCamerasOptions(args), std::cout, std::cerr);
    if (command == "print-tag") return runPrintTag(parsePrintTagOptions(args), std::cout, std::cerr);
    if (command == "calibrate-camera") return runCalibrateCamera(parseCalibrateCameraOptions(args), std::cout, std::cerr);
    throw UsageError("unknown command '" + printable(command) + "' (see probelight --help)");
  } catch (const HelpRequested& help) {  // `probelight COMMAND --help` or -h
    std::cout << help.text;
    return 0;
  } catch (const UsageError& error) {
    std::cerr << logPrefix(LogPriority::kError) << "probelight: " << error.what() << "\n";
    return 2;
  }
}
