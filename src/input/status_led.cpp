#include "input/status_led.hpp"

#include <cmath>

namespace probelight {

LedPattern ledPatternFor(bool recalibrating, bool camera_lost) {
  if (camera_lost) return LedPattern::kBlink;
  return recalibrating ? LedPattern::kOn : LedPattern::kOff;
}

bool ledLitAt(LedPattern pattern, double time_s) {
  switch (pattern) {
    case LedPattern::kOff: return false;
    case LedPattern::kOn: return true;
    case LedPattern::kBlink: return std::fmod(std::fmod(time_s, 0.5) + 0.5, 0.5) < 0.25;
  }
  return false;
}

GpioStatusLed::GpioStatusLed(StatusLedSettings settings) : settings_(std::move(settings)) {}

// The line goes dark when released (GpioOutputLine's destructor): dark
// when probelight is not running.
GpioStatusLed::~GpioStatusLed() = default;

bool GpioStatusLed::start(std::string& error) {
  if (!line_.open(settings_.chip, settings_.line, settings_.active_low, "probelight-led", error)) {
    error = "status LED: " + error;
    return false;
  }
  last_value_ = 0;
  return true;
}

void GpioStatusLed::set(bool lit) {
  const int value = lit ? 1 : 0;
  if (!line_.isOpen() || value == last_value_) return;
  // A failed write (the chip gone) leaves the LED as it was: it is a hint,
  // never a reason to stop the kiosk.
  if (line_.set(lit)) last_value_ = value;
}

}  // namespace probelight
