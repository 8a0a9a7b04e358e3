// Running the real probelight binary from a test: a scratch folder per test,
// the command's exit status and stderr, and the report it wrote.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

// Whether this build (the tests and the binary alike) runs under ASan,
// whose allocator serves malloc instead of glibc's.
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PROBELIGHT_TEST_UNDER_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define PROBELIGHT_TEST_UNDER_ASAN 1
#endif

namespace probelight::testing {

struct CommandResult {
  int exit_status = -1;
  std::string stderr_text;
};

// How often `needle` occurs in `text` ("said once" checks).
inline std::size_t countOccurrences(const std::string& text, const std::string& needle) {
  std::size_t count = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++count;
  return count;
}

// A test with its own scratch folder, /tmp/probelight_<prefix>_<pid>_<test>.
// It is removed after a passing test and kept after a failing one, or always
// with PROBELIGHT_KEEP_TEST_DIRS=1 (README's example pictures were made so).
class BinaryTest : public ::testing::Test {
 protected:
  explicit BinaryTest(std::string prefix) : prefix_(std::move(prefix)) {}

  void SetUp() override {
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(name.begin(), name.end(), '/', '_');
    dir_ = std::filesystem::temp_directory_path() /
           ("probelight_" + prefix_ + "_" + std::to_string(getpid()) + "_" + name);
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    if (std::getenv("PROBELIGHT_KEEP_TEST_DIRS")) {
      std::cout << "[ kept     ] " << dir_.string() << "\n";
      return;
    }
    if (!HasFailure()) std::filesystem::remove_all(dir_);
  }

  // `probelight ARGS`, stdout discarded.
  CommandResult run(const std::string& args) const { return runWrapped("", args); }

  // `WRAPPER probelight ARGS` (e.g. "timeout -s TERM 5"), stdout discarded.
  CommandResult runWrapped(const std::string& wrapper, const std::string& args) const {
    const std::filesystem::path err = dir_ / "stderr.txt";
    const std::string command =
        wrapper + " " + std::string(PROBELIGHT_BINARY) + " " + args + " 2>" + err.string() + " >/dev/null";
    const int status = std::system(command.c_str());
    CommandResult result;
    result.exit_status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream in(err);
    std::stringstream text;
    text << in.rdbuf();
    result.stderr_text = text.str();
    return result;
  }

  // Throws, and so fails the test, on malformed JSON (NaN included).
  nlohmann::json readReport(const std::filesystem::path& out) const {
    std::ifstream in(out / "report.json");
    return nlohmann::json::parse(in);
  }

  std::filesystem::path dir_;

 private:
  std::string prefix_;
};

}  // namespace probelight::testing
