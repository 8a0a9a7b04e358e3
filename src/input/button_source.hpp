// The button seam. A press means "recalibrate the lights"; a long press
// "go back to the stored lighting". Implementations: `none`, `key` (lines on
// stdin or a FIFO, for desktops and tests), `gpio` (the board's button,
// input/gpio_button.hpp).
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace probelight {

struct ButtonEvent {
  enum class Kind { kPress, kLongPress };
  Kind kind = Kind::kPress;
  std::chrono::steady_clock::time_point time;
};

class ButtonSource {
 public:
  virtual ~ButtonSource() = default;
  // Opens the input. On failure returns false with a one-line reason.
  virtual bool start(std::string& error) = 0;
  // Events since the last call, oldest first. Never blocks.
  virtual std::vector<ButtonEvent> poll() = 0;
  virtual std::string name() const = 0;
};

class NoButton final : public ButtonSource {
 public:
  bool start(std::string&) override { return true; }
  std::vector<ButtonEvent> poll() override { return {}; }
  std::string name() const override { return "none"; }
};

// Reads text from stdin ("-") or a FIFO/file path on a thread of its own.
// A line starting with 'r', or an empty line (bare Enter), is a press; a line
// starting with 'l' is a long press. Other lines are reported to stderr and
// ignored.
// A FIFO is reopened when its writer closes it, so tests and scripts can write
// to it repeatedly.
class KeyButton final : public ButtonSource {
 public:
  explicit KeyButton(std::string path);  // "-" for stdin
  ~KeyButton() override;
  bool start(std::string& error) override;
  std::vector<ButtonEvent> poll() override;
  std::string name() const override { return "key"; }

  // Pure parsing, exposed for tests: the event a line means, if any.
  static bool parseLine(const std::string& line, ButtonEvent::Kind& kind);

 private:
  void readLoop();

  std::string path_;
  int fd_ = -1;
  int wake_pipe_[2] = {-1, -1};
  std::thread thread_;
  std::mutex mutex_;
  std::vector<ButtonEvent> pending_;
  std::atomic<bool> stopping_{false};
};

struct GpioButtonSettings;

// Factory by configuration name: "none", "key" (reading key_path) or "gpio"
// (the line `gpio` names).
std::unique_ptr<ButtonSource> makeButtonSource(const std::string& kind, const std::string& key_path,
                                               const GpioButtonSettings& gpio, std::string& error);

}  // namespace probelight
