// The systemd service: the unit file through systemd-analyze (verify, and the
// hardening score), and the kiosk's notifications through a real
// NOTIFY_SOCKET: READY=1 after the first frame, the watchdog, STOPPING=1.
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "binary_test_support.hpp"

namespace probelight {
namespace {

namespace fs = std::filesystem;
const fs::path kUnit = fs::path(PROBELIGHT_TEST_DATA_DIR) / ".." / ".." / "systemd" / "probelight.service";

std::string runCapturing(const std::string& command, int& status) {
  std::string output;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) {
    status = -1;
    return output;
  }
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe)) output += buffer;
  status = ::pclose(pipe);
  return output;
}

bool haveSystemdAnalyze() {
  int status = 0;
  runCapturing("command -v systemd-analyze", status);
  return status == 0;
}

class ServiceUnit : public testing::BinaryTest {
 protected:
  ServiceUnit() : BinaryTest("service") {}
};

// `systemd-analyze verify` checks every directive and that ExecStart's
// program exists and is executable; the unit names the installed path, so
// the test checks a copy pointing at the binary just built.
TEST_F(ServiceUnit, VerifiesCleanly) {
  if (!haveSystemdAnalyze()) GTEST_SKIP() << "systemd-analyze is not installed";
  std::ifstream in(kUnit);
  std::stringstream text;
  text << in.rdbuf();
  const std::string unit = std::regex_replace(text.str(), std::regex("/usr/bin/probelight"), PROBELIGHT_BINARY);
  ASSERT_NE(unit, text.str()) << "ExecStart must name /usr/bin/probelight";
  const fs::path copy = dir_ / "probelight.service";
  std::ofstream(copy) << unit;
  int status = 0;
  const std::string output = runCapturing("cd " + dir_.string() + " && systemd-analyze verify " + copy.string(), status);
  EXPECT_EQ(status, 0) << output;
  EXPECT_TRUE(output.empty()) << output;
  // What the kiosk needs from it.
  for (const char* line : {"Type=notify", "WatchdogSec=", "Restart=on-failure", "User=probelight",
                           "SupplementaryGroups=video render gpio", "StateDirectory=probelight"})
    EXPECT_NE(unit.find(line), std::string::npos) << line;
}

// The aim: an exposure score of 2.0 or less.
TEST_F(ServiceUnit, HardeningScoreIsTwoOrLess) {
  if (!haveSystemdAnalyze()) GTEST_SKIP() << "systemd-analyze is not installed";
  int status = 0;
  const std::string output = runCapturing("cd " + dir_.string() + " && systemd-analyze security --offline=true " +
                                              kUnit.string(), status);
  std::smatch match;
  ASSERT_TRUE(std::regex_search(output, match, std::regex("Overall exposure level for probelight.service: ([0-9.]+)")))
      << output;
  const double score = std::stod(match[1]);
  std::printf("[ service  ] systemd-analyze security: %.1f\n", score);
  EXPECT_LE(score, 2.0) << output;
}

// A datagram socket standing in for systemd's notify socket, drained while
// the kiosk runs (as systemd does: an AF_UNIX datagram socket queues only a
// few messages, and then the sender blocks). Each message with the time it
// came, and NOTIFY_SOCKET / WATCHDOG_USEC set for the commands run meanwhile.
class NotifyListener {
 public:
  struct Message {
    std::string text;
    double at_s;  // since the listener started
  };

  NotifyListener(const fs::path& socket_path, long long watchdog_usec) : start_(std::chrono::steady_clock::now()) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::strncpy(address.sun_path, socket_path.c_str(), sizeof(address.sun_path) - 1);
    bound_ = fd_ >= 0 && socket_path.string().size() < sizeof(address.sun_path) &&
             ::bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0;
    reader_ = std::thread([this] {
      while (!done_) {
        pollfd poll_fd{fd_, POLLIN, 0};
        if (::poll(&poll_fd, 1, 20) > 0) drain();
      }
      drain();
    });
    ::setenv("NOTIFY_SOCKET", socket_path.c_str(), 1);
    ::setenv("WATCHDOG_USEC", std::to_string(watchdog_usec).c_str(), 1);
  }
  ~NotifyListener() { finish(); }

  bool bound() const { return bound_; }
  // Stops listening; the messages are complete after this.
  const std::vector<Message>& finish() {
    if (reader_.joinable()) {
      ::unsetenv("NOTIFY_SOCKET");
      ::unsetenv("WATCHDOG_USEC");
      done_ = true;
      reader_.join();
      if (fd_ >= 0) ::close(fd_);
    }
    return messages_;
  }

 private:
  void drain() {
    char buffer[4096];
    for (ssize_t n; fd_ >= 0 && (n = ::recv(fd_, buffer, sizeof buffer, MSG_DONTWAIT)) > 0;)
      messages_.push_back({std::string(buffer, static_cast<std::size_t>(n)),
                           std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count()});
  }

  std::chrono::steady_clock::time_point start_;
  int fd_ = -1;
  bool bound_ = false;
  std::atomic<bool> done_{false};
  std::vector<Message> messages_;
  std::thread reader_;
};

// The kiosk, run with NOTIFY_SOCKET and WATCHDOG_USEC pointing at a
// listener, must say READY=1 once, ping the watchdog, and say STOPPING=1 at
// the end.
TEST_F(ServiceUnit, KioskNotifiesReadyWatchdogAndStopping) {
  NotifyListener listener(dir_ / "notify.sock", 100000);  // 100 ms: pings at least every 50 ms
  ASSERT_TRUE(listener.bound());
  const testing::CommandResult result = run("run --frames 20 --save-every 0 --quiet --out " + (dir_ / "out").string());
  const std::vector<NotifyListener::Message>& messages = listener.finish();
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  int ready = 0, watchdog = 0, stopping = 0, first_ready = -1, first_watchdog = -1;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (messages[i].text.find("READY=1") != std::string::npos) {
      ++ready;
      if (first_ready < 0) first_ready = static_cast<int>(i);
    }
    if (messages[i].text.find("WATCHDOG=1") != std::string::npos) {
      ++watchdog;
      if (first_watchdog < 0) first_watchdog = static_cast<int>(i);
    }
    if (messages[i].text.find("STOPPING=1") != std::string::npos) ++stopping;
  }
  EXPECT_EQ(ready, 1);
  // 20 frames take well over 50 ms on any machine.
  EXPECT_GE(watchdog, 1);
  EXPECT_LT(first_ready, first_watchdog) << "ready comes with the first frame shown, before any ping";
  EXPECT_EQ(stopping, 1);
  ASSERT_FALSE(messages.empty());
  EXPECT_NE(messages.back().text.find("STOPPING=1"), std::string::npos);
}

// A camera that stays open but delivers nothing for 8 s (less than the 10 s
// after which the kiosk re-opens it): the service is alive, so the watchdog
// keeps being fed through the silence (every gap between pings under the
// 5 s limit; without the pings the gap would be the whole 8 s), the screen
// says why the picture is still, and the run goes on with no loss.
TEST_F(ServiceUnit, ASilentCameraKeepsTheWatchdogFedAndSaysSo) {
  const fs::path config = dir_ / "silent.yaml";
  std::ofstream(config) << "%YAML:1.0\n---\noutput:\n  save_every: 0\nsim:\n  camera_silent_at_frame: 6\n"
                           "  camera_silent_s: 8\n";
  NotifyListener listener(dir_ / "notify.sock", 5000000);
  ASSERT_TRUE(listener.bound());
  const testing::CommandResult result =
      run("run --source sim --display headless --frames 12 --config " + config.string() + " --out " +
          (dir_ / "silent").string());
  const std::vector<NotifyListener::Message>& messages = listener.finish();
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("no frame from sim:"), std::string::npos) << result.stderr_text;
  std::vector<double> pings;
  bool said_why = false;
  for (const NotifyListener::Message& message : messages) {
    if (message.text.find("WATCHDOG=1") != std::string::npos) pings.push_back(message.at_s);
    if (message.text.find("STATUS=No frame from the camera for ") != std::string::npos) said_why = true;
  }
  EXPECT_TRUE(said_why) << "no status about the silent camera";
  ASSERT_GE(pings.size(), 3u) << "an 8 s silence at a 2.5 s ping interval";
  for (std::size_t i = 1; i < pings.size(); ++i)
    EXPECT_LT(pings[i] - pings[i - 1], 5.0) << "watchdog gap between pings " << i - 1 << " and " << i;
  const nlohmann::json report = readReport(dir_ / "silent");
  EXPECT_EQ(report["frames"], 12);
  EXPECT_EQ(report["camera"]["losses"], 0);
}

// Under systemd (JOURNAL_STREAM names stderr's device and inode) every line
// carries its journald priority: a warning <4>, the rest <6>; a bad flag, an
// error, <3>. Without it, lines stay plain.
TEST_F(ServiceUnit, StderrLinesCarryJournalPrioritiesUnderSystemd) {
  // The binary's stderr is this file (BinaryTest::run redirects it there).
  const fs::path err = dir_ / "stderr.txt";
  std::ofstream(err).close();
  struct stat status {};
  ASSERT_EQ(::stat(err.c_str(), &status), 0);
  ::setenv("JOURNAL_STREAM", (std::to_string(status.st_dev) + ":" + std::to_string(status.st_ino)).c_str(), 1);
  // BinaryTest::run writes stderr to dir_/stderr.txt with `2>`, which
  // truncates the same inode: the identity holds.
  const testing::CommandResult warned = run("run --frames 2 --save-every 0 --button gpio --out " + (dir_ / "out").string());
  const testing::CommandResult bad = run("run --frames nope");
  ::unsetenv("JOURNAL_STREAM");
  ASSERT_EQ(warned.exit_status, 0) << warned.stderr_text;
  std::istringstream lines(warned.stderr_text);
  int warnings = 0, infos = 0;
  for (std::string line; std::getline(lines, line);) {
    ASSERT_TRUE(line.rfind("<4>", 0) == 0 || line.rfind("<6>", 0) == 0) << line;
    warnings += line.rfind("<4>", 0) == 0 ? 1 : 0;
    infos += line.rfind("<6>", 0) == 0 ? 1 : 0;
  }
  if (!fs::exists("/dev/gpiochip0")) {
    EXPECT_EQ(warnings, 1) << warned.stderr_text;  // the missing button
  }
  EXPECT_GE(infos, 2);
  EXPECT_EQ(bad.exit_status, 2);
  EXPECT_EQ(bad.stderr_text.rfind("<3>probelight: ", 0), 0u) << bad.stderr_text;
  // And plain without the journal.
  const testing::CommandResult plain = run("run --frames nope");
  EXPECT_EQ(plain.stderr_text.rfind("probelight: ", 0), 0u) << plain.stderr_text;
}

// `systemctl stop` sends SIGTERM: an endless run ends between frames with
// exit status 0 and its report written, rather than dying mid-frame.
TEST_F(ServiceUnit, SigtermEndsAnEndlessRunCleanlyWithItsReport) {
  const fs::path out = dir_ / "out";
  // timeout sends SIGTERM after 6 s and, with --preserve-status, exits with
  // the kiosk's own status.
  const testing::CommandResult result = runWrapped("timeout --preserve-status -s TERM 6",
                                                   "run --frames 0 --save-every 0 --out " + out.string());
  EXPECT_EQ(result.exit_status, 0) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("SIGTERM: stopping after"), std::string::npos) << result.stderr_text;
  ASSERT_TRUE(fs::exists(out / "report.json")) << result.stderr_text;
  EXPECT_GT(readReport(out)["frames"].get<long long>(), 0);
}

}  // namespace
}  // namespace probelight
