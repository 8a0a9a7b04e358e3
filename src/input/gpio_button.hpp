// The board's push button on a GPIO line, through libgpiod (v1 or v2:
// input/gpio_lines.hpp): the line is requested with pull-up bias and
// active-low (the button shorts it to ground), edge events on both edges are
// read on a thread of their own and turned into presses by ButtonDebouncer.
#pragma once

#include <atomic>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "input/button_source.hpp"
#include "input/debounce.hpp"
#include "input/gpio_lines.hpp"

namespace probelight {

struct GpioButtonSettings {
  std::string chip = "gpiochip0";  // name, number, path or label (input/gpio_lines.hpp)
  int line = 17;                   // BCM 17: header pin 11, next to ground on pin 9
  DebounceSettings debounce;
};

class GpioButton final : public ButtonSource {
 public:
  explicit GpioButton(GpioButtonSettings settings);
  ~GpioButton() override;
  // False, with a one-line reason naming the chip and line and the usual
  // causes, when the chip or the line cannot be had.
  bool start(std::string& error) override;
  std::vector<ButtonEvent> poll() override;
  std::string name() const override;

 private:
  void readLoop();

  GpioButtonSettings settings_;
  GpioInputLine line_;
  std::thread thread_;
  std::mutex mutex_;
  std::vector<ButtonEvent> pending_;
  std::atomic<bool> stopping_{false};
};

}  // namespace probelight
