// `probelight cameras` through the binary, with libcamera's real camera
// manager. A machine without a video device (this one, CI's) must get the
// one line that says so, exit 0; one with a camera must get its listing
// (the board VM checks vimc's: scripts/board_vm/guest/checks.sh).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <sys/wait.h>

#include "binary_test_support.hpp"

namespace probelight {
namespace {

class ListCameras : public testing::BinaryTest {
 protected:
  ListCameras() : BinaryTest("cameras") {}
};

bool anyVideoDevice() {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", ec))
    if (entry.path().filename().string().rfind("video", 0) == 0) return true;
  return false;
}

TEST_F(ListCameras, SaysInOneLineWhenThereIsNoCameraAndListsThemOtherwise) {
  const std::filesystem::path out = dir_ / "out.txt", err = dir_ / "err.txt";
  const int status =
      std::system((std::string(PROBELIGHT_BINARY) + " cameras >" + out.string() + " 2>" + err.string()).c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  // libcamera's own INFO and WARN lines are kept off (LIBCAMERA_LOG_LEVELS).
  EXPECT_EQ(std::filesystem::file_size(err), 0u);
  std::ifstream in(out);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_FALSE(lines.empty());
  if (!anyVideoDevice()) {
    ASSERT_EQ(lines.size(), 1u) << lines[1];
    EXPECT_NE(lines[0].find("libcamera found no camera"), std::string::npos) << lines[0];
  } else {
    EXPECT_NE(lines[0].find("camera"), std::string::npos);
    ASSERT_GE(lines.size(), 3u);
    EXPECT_EQ(lines[2].rfind("   id: ", 0), 0u) << lines[2];
  }
  // Flags it does not take: exit 2, naming the flag.
  const testing::CommandResult bad = run("cameras --list");
  EXPECT_EQ(bad.exit_status, 2);
  EXPECT_NE(bad.stderr_text.find("'--list'"), std::string::npos) << bad.stderr_text;
}

}  // namespace
}  // namespace probelight
