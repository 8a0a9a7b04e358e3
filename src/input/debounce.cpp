#include "input/debounce.hpp"

#include <algorithm>
#include <cmath>

namespace probelight {

ButtonDebouncer::ButtonDebouncer(DebounceSettings settings, bool initially_pressed)
    : debounce_ns_(static_cast<std::int64_t>(std::max(0.0, settings.debounce_ms) * 1e6)),
      long_press_ns_(static_cast<std::int64_t>(std::max(0.0, settings.long_press_ms) * 1e6)),
      raw_pressed_(initially_pressed),
      stable_pressed_(initially_pressed),
      // A button already held when we start is not a press we saw begin.
      long_press_fired_(initially_pressed) {}

void ButtonDebouncer::settle(std::int64_t now_ns, std::vector<ButtonEvent::Kind>& events) {
  // A level held for debounce_ns becomes the stable one, as of when it was
  // reached plus the debounce time.
  if (raw_pressed_ != stable_pressed_ && now_ns - raw_since_ns_ >= debounce_ns_) {
    stable_pressed_ = raw_pressed_;
    if (stable_pressed_) {
      pressed_since_ns_ = raw_since_ns_;
      long_press_fired_ = false;
    } else {
      if (!long_press_fired_) events.push_back(ButtonEvent::Kind::kPress);
      long_press_fired_ = false;
    }
  }
  if (stable_pressed_ && !long_press_fired_ && now_ns - pressed_since_ns_ >= long_press_ns_) {
    long_press_fired_ = true;
    events.push_back(ButtonEvent::Kind::kLongPress);
  }
}

std::vector<ButtonEvent::Kind> ButtonDebouncer::onLevel(std::int64_t time_ns, bool pressed) {
  std::vector<ButtonEvent::Kind> events;
  if (!started_) {
    started_ = true;
    raw_since_ns_ = time_ns;
  }
  settle(time_ns, events);  // what was due before this edge
  if (pressed != raw_pressed_) {
    raw_pressed_ = pressed;
    raw_since_ns_ = time_ns;
  }
  settle(time_ns, events);
  return events;
}

std::vector<ButtonEvent::Kind> ButtonDebouncer::onTime(std::int64_t now_ns) {
  std::vector<ButtonEvent::Kind> events;
  if (!started_) {
    started_ = true;
    raw_since_ns_ = now_ns;
  }
  settle(now_ns, events);
  return events;
}

}  // namespace probelight
