// GPIO lines through libgpiod, in one place for both of its APIs: v1
// (Debian and Raspberry Pi OS bookworm ship 1.6) and v2 (2.x, in newer
// distributions), chosen at build time (PROBELIGHT_LIBGPIOD_V2, set by CMake
// from pkg-config's version). The button and the status LED use these and
// never libgpiod itself.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace probelight {

// A chip as configured ("gpiochip0", "0", "/dev/gpiochip4") as a device
// path; nullopt for anything else, which is taken as the chip's label
// ("pinctrl-rp1") and looked up among the chips.
std::optional<std::string> gpioChipPath(const std::string& chip);

// "libgpiod 1.6.3 (v1 API)": which library the build uses.
std::string gpioLibraryDescription();

struct GpioHandles;  // the library's objects, per API

// An input with pull-up bias, active-low (the button shorts it to ground),
// reporting both edges.
class GpioInputLine {
 public:
  GpioInputLine();
  ~GpioInputLine();
  GpioInputLine(const GpioInputLine&) = delete;
  GpioInputLine& operator=(const GpioInputLine&) = delete;

  // False with one line saying why (chip not found, no such line, busy).
  bool open(const std::string& chip, int line, const std::string& consumer, std::string& error);
  // 1: an edge is pending; 0: none within the timeout; -1: the chip is gone.
  int waitEdge(std::int64_t timeout_ns);
  // Consumes pending edge events (their types are not used: the level is
  // read back, which means the same on every kernel).
  void discardEdges();
  // The logical level: 1 while the button is held, 0 released, -1 error.
  int level();

 private:
  GpioHandles* handles_;
  unsigned offset_ = 0;
};

// An output, optionally active-low.
class GpioOutputLine {
 public:
  GpioOutputLine();
  ~GpioOutputLine();
  GpioOutputLine(const GpioOutputLine&) = delete;
  GpioOutputLine& operator=(const GpioOutputLine&) = delete;

  bool open(const std::string& chip, int line, bool active_low, const std::string& consumer, std::string& error);
  bool isOpen() const;
  // The logical level; false when the write failed.
  bool set(bool active);

 private:
  GpioHandles* handles_;
  unsigned offset_ = 0;
};

}  // namespace probelight
