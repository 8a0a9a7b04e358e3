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
#include "input/key_line_reader.hpp"

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

// 10 MB without a newline used to be buffered whole (+23 MB RSS) and echoed
// to the log raw, escape sequences and all (issue 15, D15).
TEST(KeyLineReader, AnEndlessLineStaysBoundedAndIsIgnoredWhole) {
  KeyLineReader reader;
  const std::string chunk(4096, 'r');  // "rrrr...": would parse as a press if it were not cut
  for (int i = 0; i < 2560; ++i) {  // 10 MiB
    EXPECT_TRUE(reader.feed(chunk.data(), chunk.size()).empty());
    ASSERT_LE(reader.pendingBytes(), KeyLineReader::kMaxLineBytes);
  }
  const std::vector<KeyLineReader::Line> lines = reader.feed("x\nr\n", 4);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_TRUE(lines[0].cut);
  EXPECT_EQ(lines[0].text.size(), KeyLineReader::kMaxLineBytes);
  EXPECT_FALSE(lines[1].cut);  // the next line is whole again
  EXPECT_EQ(lines[1].text, "r");
  EXPECT_EQ(KeyLineReader::printable(lines[0].text, lines[0].cut), std::string(40, 'r') + "...");
}

TEST(KeyLineReader, ControlAndEscapeBytesAreShownAsHexNotSentToTheTerminal) {
  const std::string hostile = "\x1b[2J\x1b]0;owned\x07\r\\\xff ok";
  const std::string shown = KeyLineReader::printable(hostile);
  EXPECT_EQ(shown, "\\x1B[2J\\x1B]0;owned\\x07\\x0D\\x5C\\xFF ok");
  for (char c : shown) EXPECT_TRUE(c >= 0x20 && c < 0x7F) << static_cast<int>(c);
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
