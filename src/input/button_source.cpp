#include "input/button_source.hpp"
#include "input/gpio_button.hpp"
#include "input/key_line_reader.hpp"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <iostream>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

namespace probelight {

KeyButton::KeyButton(std::string path) : path_(std::move(path)) {}

KeyButton::~KeyButton() {
  stopping_ = true;
  if (wake_pipe_[1] >= 0) {
    const char byte = 'q';
    (void)!write(wake_pipe_[1], &byte, 1);
  }
  if (thread_.joinable()) thread_.join();
  if (fd_ > 0) close(fd_);
  for (int fd : wake_pipe_)
    if (fd >= 0) close(fd);
}

bool KeyButton::parseLine(const std::string& line, ButtonEvent::Kind& kind) {
  size_t first = line.find_first_not_of(" \t\r");
  if (first == std::string::npos) {  // bare Enter
    kind = ButtonEvent::Kind::kPress;
    return true;
  }
  const char c = line[first];
  if (c == 'r' || c == 'R') {
    kind = ButtonEvent::Kind::kPress;
    return true;
  }
  if (c == 'l' || c == 'L') {
    kind = ButtonEvent::Kind::kLongPress;
    return true;
  }
  return false;
}

bool KeyButton::start(std::string& error) {
  if (pipe(wake_pipe_) != 0) {
    error = std::string("key button: cannot create a pipe: ") + std::strerror(errno);
    return false;
  }
  if (path_ == "-" || path_.empty()) {
    fd_ = STDIN_FILENO;
  } else {
    struct stat info {};
    if (stat(path_.c_str(), &info) != 0) {
      error = "key button: " + path_ + ": " + std::strerror(errno) + " (create it with mkfifo, or use --button none)";
      return false;
    }
    // O_RDWR on a FIFO keeps a writer open ourselves, so the read end never
    // sees end-of-file between the writes of separate `echo r > fifo` calls.
    fd_ = open(path_.c_str(), (S_ISFIFO(info.st_mode) ? O_RDWR : O_RDONLY) | O_CLOEXEC);
    if (fd_ < 0) {
      error = "key button: cannot open " + path_ + ": " + std::strerror(errno);
      return false;
    }
  }
  thread_ = std::thread([this] { readLoop(); });
  return true;
}

void KeyButton::readLoop() {
  KeyLineReader reader;
  char buffer[256];
  while (!stopping_) {
    pollfd fds[2] = {{fd_, POLLIN, 0}, {wake_pipe_[0], POLLIN, 0}};
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      return;
    }
    if (fds[1].revents) return;
    if (!(fds[0].revents & (POLLIN | POLLHUP))) continue;
    ssize_t n = read(fd_, buffer, sizeof buffer);
    if (n <= 0) return;  // end of stdin or of a regular file: no more presses
    for (const KeyLineReader::Line& line : reader.feed(buffer, static_cast<std::size_t>(n))) {
      ButtonEvent::Kind kind;
      if (!line.cut && parseLine(line.text, kind)) {
        std::lock_guard<std::mutex> lock(mutex_);
        pending_.push_back({kind, std::chrono::steady_clock::now()});
      } else {
        std::cerr << "probelight: key button: ignoring input '" << KeyLineReader::printable(line.text, line.cut)
                  << "' (r or Enter = recalibrate)\n";
      }
    }
  }
}

std::vector<ButtonEvent> KeyButton::poll() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<ButtonEvent> events;
  events.swap(pending_);
  return events;
}

std::unique_ptr<ButtonSource> makeButtonSource(const std::string& kind, const std::string& key_path,
                                               const GpioButtonSettings& gpio, std::string& error) {
  if (kind == "none") return std::make_unique<NoButton>();
  if (kind == "key") return std::make_unique<KeyButton>(key_path.empty() ? "-" : key_path);
  if (kind == "gpio") return std::make_unique<GpioButton>(gpio);
  error = "unknown button source '" + kind + "' (choose none, key or gpio)";
  return nullptr;
}

}  // namespace probelight
