#include <gtest/gtest.h>

#include <functional>

#include "app/command_line.hpp"

namespace probelight {
namespace {

TEST(CommandLine, ParsesTheReadmeRunCommand) {
  RunOptions options = parseRunOptions({"--source", "sim", "--display", "headless", "--frames", "300", "--out", "o"});
  EXPECT_EQ(options.source, "sim");
  EXPECT_EQ(options.frames, 300);
  EXPECT_EQ(options.out_dir, "o");
}

TEST(CommandLine, AcceptsFlagEqualsValue) {
  RunOptions options = parseRunOptions({"--frames=12", "--button=key", "--key-input=/tmp/fifo"});
  EXPECT_EQ(options.frames, 12);
  EXPECT_EQ(options.button, "key");
  EXPECT_EQ(options.key_path, "/tmp/fifo");
}

// Issue 20: --camera named the calibration file; --calibration does now,
// --camera stays one release as its alias and says so once, and
// --camera-id picks the camera.
TEST(CommandLine, CalibrationFlagAndItsDeprecatedAlias) {
  RunOptions renamed = parseRunOptions({"--calibration", "cam.yaml", "--camera-id", "/base/usb@1"});
  EXPECT_EQ(renamed.camera_path, "cam.yaml");
  EXPECT_EQ(renamed.camera_id, "/base/usb@1");
  EXPECT_TRUE(renamed.warnings.empty());
  RunOptions old_name = parseRunOptions({"--camera", "old.yaml", "--camera=again.yaml"});
  EXPECT_EQ(old_name.camera_path, "again.yaml");
  ASSERT_EQ(old_name.warnings.size(), 1u);  // once, however often it is given
  EXPECT_NE(old_name.warnings[0].find("--camera is deprecated"), std::string::npos);
  EXPECT_NE(old_name.warnings[0].find("--calibration"), std::string::npos);
  AnalyzeOptions analyze = parseAnalyzeOptions({"--frame", "f.png", "--camera", "c.yaml", "--rig", "r.yaml", "--out", "o"});
  EXPECT_EQ(analyze.camera_path, "c.yaml");
  EXPECT_EQ(analyze.warnings.size(), 1u);
  RenderOptions render = parseRenderOptions({"--frame", "f.png", "--calibration", "c.yaml", "--rig", "r.yaml", "--out",
                                             "o", "--object", "sphere", "--radius", "0.03"});
  EXPECT_EQ(render.frame.camera_path, "c.yaml");
  EXPECT_TRUE(render.frame.warnings.empty());
  // The messages that ask for it give the new name.
  try {
    parseRunOptions({"--source", "images", "--images", "x/*.png", "--rig", "r.yaml"});
    ADD_FAILURE() << "no error";
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("needs --calibration camera.yaml"), std::string::npos) << error.what();
  }
}

// What `probelight run ARGS` says is wrong with its flags ("no error": nothing).
std::string message(const std::vector<std::string>& args) {
  try {
    parseRunOptions(args);
  } catch (const UsageError& error) {
    return std::string(error.what());
  }
  return std::string("no error");
}

TEST(CommandLine, BadFlagsNameTheFlag) {
  EXPECT_NE(message({"--bogus"}).find("'--bogus'"), std::string::npos);
  EXPECT_NE(message({"--frames", "ten"}).find("--frames"), std::string::npos);
  EXPECT_NE(message({"--frames", "-3"}).find("--frames"), std::string::npos);
  // Issue 15, D14: 2^31 used to wrap to INT_MIN.
  EXPECT_NE(message({"--save-every", "2147483648"}).find("flag --save-every: must be at most 2147483647"),
            std::string::npos)
      << message({"--save-every", "2147483648"});
  EXPECT_EQ(parseRunOptions({"--save-every", "2147483647"}).save_every, 2147483647);
  EXPECT_NE(message({"--frames"}).find("needs a value"), std::string::npos);
  EXPECT_NE(message({"--source", "webcam"}).find("--source"), std::string::npos);
  EXPECT_NE(message({"--source", "images"}).find("--images"), std::string::npos);
  EXPECT_NE(message({"--source", "images", "--images", "x/*.png"}).find("--calibration"), std::string::npos);
  for (const auto& args : std::vector<std::vector<std::string>>{{"--bogus"}, {"--frames", "ten"}})
    EXPECT_EQ(message(args).find('\n'), std::string::npos) << "one line";
}

// Found by the command-line fuzzer (fuzz/): an argument holding a newline
// or a terminal escape made a usage error of two lines, or one that rewrote
// the terminal. Echoed arguments keep their bytes as C escapes (argv holds
// no NUL, so none is tested).
TEST(CommandLine, ArgumentsWithControlCharactersGiveOnePrintableLine) {
  std::string bracket_error;
  try {
    parseAnalyzeOptions({"--frame", "f.png", "--calibration", "c.yaml", "--rig", "r.yaml", "--out", "o", "--bracket",
                         "\xc0\n\x01x@"});
  } catch (const UsageError& error) {
    bracket_error = error.what();
  }
  EXPECT_NE(bracket_error.find("--bracket"), std::string::npos) << bracket_error;
  EXPECT_NE(bracket_error.find("\\n\\x01x@"), std::string::npos) << bracket_error;
  for (const std::string& text : {message({"--frames", "1\n2"}), message({"--bogus\x1b[2J"}), bracket_error}) {
    EXPECT_FALSE(text.empty());
    for (const char c : text) EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20 || c == 0x7f) << text;
  }
  EXPECT_EQ(printable(std::string("a\tb\x7f\n", 5)), "a\\tb\\x7f\\n");
}

// -h and --help, for every command: HelpRequested with that command's own
// flags, each on a line with its description.
TEST(CommandLine, HelpForEveryCommandWithLongAndShortFlag) {
  using Parse = std::function<void(const std::vector<std::string>&)>;
  const struct {
    std::string command;
    Parse parse;
    std::vector<std::string> own_flags;
    std::string not_its_flag;
  } commands[] = {
      {"run", [](auto& args) { parseRunOptions(args); }, {"--frames", "-n,", "--source", "--quiet", "(default 300)"}, "--bracket"},
      {"analyze", [](auto& args) { parseAnalyzeOptions(args); }, {"--bracket", "--frame", "--no-white-ref"}, "--radius"},
      {"render", [](auto& args) { parseRenderOptions(args); }, {"--bracket", "--radius", "--albedo", "sphere|box"}, "--quiet"},
      {"calibrate-camera", [](auto& args) { parseCalibrateCameraOptions(args); }, {"--board", "--square", "--images"},
       "--frames"},
  };
  for (const auto& c : commands) {
    for (const std::string help : {"--help", "-h"}) {
      // Also after other flags, even ones that would be errors: help wins.
      for (const std::vector<std::string>& args : {std::vector<std::string>{help}, std::vector<std::string>{"--bogus", help}}) {
        std::string text;
        try {
          c.parse(args);
          ADD_FAILURE() << c.command << " " << help << ": no help";
        } catch (const HelpRequested& requested) {
          text = requested.text;
        } catch (const UsageError& error) {
          ADD_FAILURE() << c.command << " " << help << ": " << error.what();
        }
        EXPECT_NE(text.find("probelight " + c.command), std::string::npos) << text;
        EXPECT_NE(text.find("-h,--help"), std::string::npos) << text;
        EXPECT_NE(text.find("exit status"), std::string::npos) << text;
        for (const auto& flag : c.own_flags) EXPECT_NE(text.find(flag), std::string::npos) << c.command << ": " << flag;
        EXPECT_EQ(text.find(c.not_its_flag), std::string::npos) << c.command << ": " << c.not_its_flag;
      }
    }
  }
}

TEST(CommandLine, OverviewListsTheCommandsAndExitStatuses) {
  const std::string text = usageText();
  for (const char* word : {"run", "analyze", "render", "calibrate-camera", "--help", "--version", "exit status", "3 (analyze, render)"})
    EXPECT_NE(text.find(word), std::string::npos) << word;
}

TEST(CommandLine, ShortFlagsParseLikeLongOnes) {
  const RunOptions longs = parseRunOptions({"--frames", "12", "--out", "o", "--config", "p.yaml", "--quiet"});
  const RunOptions shorts = parseRunOptions({"-n", "12", "-o", "o", "-c", "p.yaml", "-q"});
  const RunOptions packed = parseRunOptions({"-qn12", "-oo", "-c", "p.yaml"});
  for (const RunOptions* options : {&longs, &shorts, &packed}) {
    EXPECT_EQ(options->frames, 12);
    EXPECT_EQ(options->out_dir, "o");
    EXPECT_EQ(options->config_path, "p.yaml");
    EXPECT_TRUE(options->quiet);
  }
  EXPECT_FALSE(parseRunOptions({}).quiet);

  const AnalyzeOptions analyze = parseAnalyzeOptions({"-f", "f.png", "--calibration", "c.yaml", "--rig", "r.yaml", "-o", "o", "-c", "p.yaml"});
  EXPECT_EQ(analyze.frame_path, "f.png");
  EXPECT_EQ(analyze.out_dir, "o");
  EXPECT_EQ(analyze.config_path, "p.yaml");
  const RenderOptions render = parseRenderOptions({"-f", "f.png", "--calibration", "c.yaml", "--rig", "r.yaml", "-o", "o", "--radius", "0.03"});
  EXPECT_EQ(render.frame.frame_path, "f.png");
  EXPECT_EQ(render.frame.out_dir, "o");
  const CalibrateCameraOptions calibrate = parseCalibrateCameraOptions({"--images", "v/*.png", "--board", "9x6", "--square", "0.025", "-o", "c.yaml"});
  EXPECT_EQ(calibrate.out_path, "c.yaml");
}

TEST(CommandLine, ARepeatedFlagTakesItsLastValue) {
  const RunOptions options = parseRunOptions({"--frames", "3", "--out", "a", "-n", "7", "-o", "b", "--source=images", "--source",
                                              "sim", "--frames=9"});
  EXPECT_EQ(options.frames, 9);
  EXPECT_EQ(options.out_dir, "b");
  EXPECT_EQ(options.source, "sim");
  const AnalyzeOptions analyze =
      parseAnalyzeOptions({"--frame", "a.png", "--calibration", "x.yaml", "--calibration", "c.yaml", "--rig", "r.yaml", "--out", "o",
                           "--bracket", "u3.png@-3", "--bracket=o2.png@2"});
  EXPECT_EQ(analyze.camera_path, "c.yaml");
  ASSERT_EQ(analyze.brackets.size(), 2u) << "--bracket adds one each time";
  EXPECT_EQ(analyze.brackets[0].path, "u3.png");
  EXPECT_EQ(analyze.brackets[1].ev, 2.0);
}

// --frame again is another view (issue 18); each --bracket belongs to the
// --frame before it, one before any --frame to the first, whatever the
// spelling (-f X, --frame X, --frame=X; --bracket X, --bracket=X).
TEST(CommandLine, EachFrameTakesTheBracketsAfterIt) {
  const AnalyzeOptions analyze = parseAnalyzeOptions(
      {"--bracket", "a3.png@-3", "--frame", "a.png", "--calibration", "c.yaml", "-f", "b.png", "--bracket=b3.png@-3",
       "--rig", "r.yaml", "--bracket", "b6.png@-6", "--frame=c.png", "--out", "o", "-f", "d.png", "--bracket",
       "d3.png@-3"});
  EXPECT_EQ(analyze.frame_path, "a.png");
  ASSERT_EQ(analyze.brackets.size(), 1u);
  EXPECT_EQ(analyze.brackets[0].path, "a3.png");
  ASSERT_EQ(analyze.more_views.size(), 3u);
  EXPECT_EQ(analyze.more_views[0].frame_path, "b.png");
  ASSERT_EQ(analyze.more_views[0].brackets.size(), 2u);
  EXPECT_EQ(analyze.more_views[0].brackets[0].path, "b3.png");
  EXPECT_EQ(analyze.more_views[0].brackets[1].ev, -6.0);
  EXPECT_EQ(analyze.more_views[1].frame_path, "c.png");
  EXPECT_TRUE(analyze.more_views[1].brackets.empty());
  EXPECT_EQ(analyze.more_views[2].frame_path, "d.png");
  ASSERT_EQ(analyze.more_views[2].brackets.size(), 1u);
  EXPECT_EQ(analyze.more_views[2].brackets[0].path, "d3.png");
  // More than 16 views is refused.
  std::vector<std::string> args = {"--calibration", "c.yaml", "--rig", "r.yaml", "--out", "o"};
  for (int i = 0; i < 17; ++i) {
    // Appended in place: GCC 12's -Wrestrict misreads "f" + std::to_string(i).
    std::string frame = std::to_string(i);
    frame.insert(0, 1, 'f');
    frame.append(".png");
    args.push_back("--frame");
    args.push_back(frame);
  }
  try {
    parseAnalyzeOptions(args);
    ADD_FAILURE() << "17 views accepted";
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("at most 16 views, got 17"), std::string::npos) << error.what();
  }
}

// An EV of 1e-300 passed the old "non-zero" check, and 40 frames of one
// view were all decoded and merged (issue 15, D17).
TEST(CommandLine, BracketEvsBelowAnEighthOfAStopAndMoreThan16FramesAreRefused) {
  auto analyzeWith = [](const std::vector<std::string>& brackets) {
    std::vector<std::string> args = {"--frame", "a.png", "--calibration", "c.yaml", "--rig", "r.yaml", "--out", "o"};
    for (const std::string& b : brackets) args.insert(args.end(), {"--bracket", b});
    try {
      parseAnalyzeOptions(args);
    } catch (const UsageError& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  for (const char* bad : {"u.png@1e-300", "u.png@0", "u.png@-0.1", "u.png@25"})
    EXPECT_NE(analyzeWith({bad}).find("EV must be 0.125 to 24 stops"), std::string::npos) << bad << ": " << analyzeWith({bad});
  EXPECT_EQ(analyzeWith({"u.png@-0.125", "o.png@24"}), "");
  std::vector<std::string> many;
  for (int i = 1; i <= 17; ++i) many.push_back("f" + std::to_string(i) + ".png@-" + std::to_string(i));
  EXPECT_NE(analyzeWith(many).find("at most 16 bracket frames, got 17"), std::string::npos) << analyzeWith(many);
  many.pop_back();
  EXPECT_EQ(analyzeWith(many), "");
}

TEST(CommandLine, UsageErrorsAreOneLineNamingTheFlag) {
  EXPECT_NE(message({"-n"}).find("flag --frames needs a value"), std::string::npos) << message({"-n"});
  EXPECT_NE(message({"--frames="}).find("flag --frames needs a value"), std::string::npos);
  EXPECT_NE(message({"--frames=", "5"}).find("flag --frames needs a value"), std::string::npos);
  EXPECT_NE(message({"-n", "ten"}).find("--frames"), std::string::npos);
  EXPECT_NE(message({"--bogus=3"}).find("'--bogus'"), std::string::npos);
  EXPECT_NE(message({"-x"}).find("'-x'"), std::string::npos);
  EXPECT_NE(message({"--quiet=no"}).find("--quiet"), std::string::npos);
  EXPECT_NE(message({"--frames", "3", "4"}).find("'4'"), std::string::npos);
  for (const auto& args : std::vector<std::vector<std::string>>{{"-n"}, {"--bogus=3"}, {"-x"}, {"--frames", "3", "4"}})
    EXPECT_EQ(message(args).find('\n'), std::string::npos) << "one line";
}

}  // namespace
}  // namespace probelight
