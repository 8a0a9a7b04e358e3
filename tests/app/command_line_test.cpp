#include <gtest/gtest.h>

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

TEST(CommandLine, BadFlagsNameTheFlag) {
  auto message = [](std::vector<std::string> args) {
    try {
      parseRunOptions(args);
    } catch (const UsageError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({"--bogus"}).find("'--bogus'"), std::string::npos);
  EXPECT_NE(message({"--frames", "ten"}).find("--frames"), std::string::npos);
  EXPECT_NE(message({"--frames", "-3"}).find("--frames"), std::string::npos);
  EXPECT_NE(message({"--frames"}).find("needs a value"), std::string::npos);
  EXPECT_NE(message({"--source", "webcam"}).find("--source"), std::string::npos);
  EXPECT_NE(message({"--source", "images"}).find("--images"), std::string::npos);
  EXPECT_NE(message({"--source", "images", "--images", "x/*.png"}).find("--camera"), std::string::npos);
  for (const auto& args : std::vector<std::vector<std::string>>{{"--bogus"}, {"--frames", "ten"}})
    EXPECT_EQ(message(args).find('\n'), std::string::npos) << "one line";
}

}  // namespace
}  // namespace probelight
