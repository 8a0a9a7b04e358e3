#include "input/window_keys.hpp"

namespace probelight {

void WindowActions::add(const WindowActions& more) {
  button.insert(button.end(), more.button.begin(), more.button.end());
  saves += more.saves;
  quit = quit || more.quit;
}

// Keys do not bounce: a debounce of 0 ms takes each edge as it comes.
WindowKeys::WindowKeys(double long_press_ms) : button_(DebounceSettings{0.0, long_press_ms}) {}

WindowActions WindowKeys::fromButton(const std::vector<ButtonEvent::Kind>& kinds) const {
  WindowActions actions;
  actions.button = kinds;
  return actions;
}

WindowActions WindowKeys::onKey(WindowKey key, bool down, bool repeat, std::int64_t time_ns) {
  WindowActions actions = fromButton(button_.onTime(time_ns));
  if (repeat) return actions;
  switch (key) {
    case WindowKey::kButton:
      actions.add(fromButton(button_.onLevel(time_ns, down)));
      break;
    case WindowKey::kSave:
      if (down) ++actions.saves;
      break;
    case WindowKey::kQuit:
      if (down) actions.quit = true;
      break;
    case WindowKey::kOther:
      break;
  }
  return actions;
}

WindowActions WindowKeys::onTime(std::int64_t now_ns) { return fromButton(button_.onTime(now_ns)); }

const char* WindowKeys::help() { return "Keys: R or space recalibrates (hold R: stored lighting), S saves, Q quits"; }

}  // namespace probelight
