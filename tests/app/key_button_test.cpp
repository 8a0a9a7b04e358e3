#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <fcntl.h>
#include <filesystem>
#include <string>
#include <sys/stat.h>
#include <thread>
#include <unistd.h>

#include "input/button_source.hpp"
#include "input/gpio_button.hpp"

namespace probelight {
namespace {

TEST(KeyButton, ParsesLines) {
  ButtonEvent::Kind kind;
  ASSERT_TRUE(KeyButton::parseLine("", kind));
  EXPECT_EQ(kind, ButtonEvent::Kind::kPress);
  ASSERT_TRUE(KeyButton::parseLine("  r", kind));
  EXPECT_EQ(kind, ButtonEvent::Kind::kPress);
  ASSERT_TRUE(KeyButton::parseLine("long", kind));
  EXPECT_EQ(kind, ButtonEvent::Kind::kLongPress);
  EXPECT_FALSE(KeyButton::parseLine("x", kind));
}

// Writes `text` to the FIFO as a separate writer, as `echo r > fifo` does.
void writeToFifo(const std::string& path, const std::string& text) {
  int fd = open(path.c_str(), O_WRONLY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(write(fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  close(fd);
}

std::vector<ButtonEvent> pollFor(ButtonSource& button, size_t wanted) {
  std::vector<ButtonEvent> events;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (events.size() < wanted && std::chrono::steady_clock::now() < deadline) {
    auto more = button.poll();
    events.insert(events.end(), more.begin(), more.end());
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return events;
}

TEST(KeyButton, FifoDeliversPressesFromSeparateWriters) {
  const auto dir = std::filesystem::temp_directory_path() / ("probelight_fifo_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string fifo = (dir / "button").string();
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  {
    KeyButton button(fifo);
    std::string error;
    ASSERT_TRUE(button.start(error)) << error;
    writeToFifo(fifo, "r\nnonsense\n");
    writeToFifo(fifo, "l\n");  // the writer closed in between: the reader must survive it
    const auto events = pollFor(button, 2);
    ASSERT_EQ(events.size(), 2u);
    EXPECT_EQ(events[0].kind, ButtonEvent::Kind::kPress);
    EXPECT_EQ(events[1].kind, ButtonEvent::Kind::kLongPress);
    EXPECT_TRUE(button.poll().empty()) << "events are delivered once";
  }
  std::filesystem::remove_all(dir);
}

TEST(KeyButton, MissingPathIsAClearError) {
  KeyButton button("/nonexistent/probelight-button");
  std::string error;
  EXPECT_FALSE(button.start(error));
  EXPECT_NE(error.find("/nonexistent/probelight-button"), std::string::npos);
  EXPECT_EQ(error.find('\n'), std::string::npos);
}

TEST(ButtonFactory, RejectsUnknownKinds) {
  std::string error;
  EXPECT_EQ(makeButtonSource("gpio-typo", "", GpioButtonSettings{}, error), nullptr);
  EXPECT_NE(error.find("gpio-typo"), std::string::npos);
  EXPECT_NE(makeButtonSource("none", "", GpioButtonSettings{}, error), nullptr);
}

}  // namespace
}  // namespace probelight
