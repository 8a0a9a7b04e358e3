// A status LED on a GPIO output line: lit while the lights recalibrate,
// blinking while the camera is lost, dark otherwise. Optional: without a
// line configured there is none, and a board whose chip or line cannot be
// had runs without it (warned once), as with the button.
#pragma once

#include <memory>
#include <string>

#include "input/gpio_lines.hpp"

namespace probelight {

struct StatusLedSettings {
  std::string chip = "gpiochip0";  // as GpioButtonSettings::chip
  int line = -1;                   // -1: no LED
  bool active_low = false;         // true when the LED is wired from 3V3 into the pin
};

enum class LedPattern { kOff, kOn, kBlink };

// What the LED shows for the kiosk's state: recalibrating on, camera lost
// blinking (it wins: nothing is being recalibrated without frames).
LedPattern ledPatternFor(bool recalibrating, bool camera_lost);
// Whether a pattern is lit at `time_s` (blinking: 2 Hz, half on).
bool ledLitAt(LedPattern pattern, double time_s);

class StatusLed {
 public:
  virtual ~StatusLed() = default;
  virtual void set(bool lit) = 0;
};

class NoStatusLed final : public StatusLed {
 public:
  void set(bool lit) override { (void)lit; }
};

class GpioStatusLed final : public StatusLed {
 public:
  explicit GpioStatusLed(StatusLedSettings settings);
  ~GpioStatusLed() override;
  // False, with a one-line reason naming the chip and line, when they
  // cannot be had.
  bool start(std::string& error);
  void set(bool lit) override;

 private:
  StatusLedSettings settings_;
  GpioOutputLine line_;
  int last_value_ = -1;
};

}  // namespace probelight
