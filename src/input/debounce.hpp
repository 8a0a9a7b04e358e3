// Turning a mechanical push button's raw edges into presses. Pure logic, fed
// with (time, level) pairs, so that bounce can be tested with synthetic edges.
//
// A contact bounces for a few milliseconds when it closes and opens. A level
// counts only once the raw input has held it for `debounce_ms`; the first
// settled change to "pressed" starts a press. Releasing before
// `long_press_ms` gives a kPress (on release: until then it could still become
// a long press); holding that long gives one kLongPress at that moment, and
// the release after it gives nothing more.
#pragma once

#include <cstdint>
#include <vector>

#include "input/button_source.hpp"

namespace probelight {

struct DebounceSettings {
  double debounce_ms = 20.0;     // contacts settle within a few ms; 20 is common practice and far below a human press
  double long_press_ms = 3000.0;
};

class ButtonDebouncer {
 public:
  explicit ButtonDebouncer(DebounceSettings settings = {}, bool initially_pressed = false);

  // A raw edge: the input reads `pressed` from `time_ns` on (monotonic ns).
  // Returns the events that are due by then.
  std::vector<ButtonEvent::Kind> onLevel(std::int64_t time_ns, bool pressed);
  // Time passing with no edge: settles a level held long enough, and fires a
  // long press when due. Call it every few milliseconds.
  std::vector<ButtonEvent::Kind> onTime(std::int64_t now_ns);

  bool pressed() const { return stable_pressed_; }

 private:
  void settle(std::int64_t now_ns, std::vector<ButtonEvent::Kind>& events);

  std::int64_t debounce_ns_;
  std::int64_t long_press_ns_;
  bool raw_pressed_;
  std::int64_t raw_since_ns_ = 0;
  bool stable_pressed_;
  std::int64_t pressed_since_ns_ = 0;  // when the current press settled
  bool long_press_fired_ = false;
  bool started_ = false;
};

}  // namespace probelight
