// The desktop window's keys, as the kiosk understands them (--display
// window). Pure: fed with key edges and the time, so it is tested without
// a window.
//   R or space: the button. A short press recalibrates; held for
//     long_press_ms, a long press (back to the stored lighting), as the
//     board's GPIO button (ButtonDebouncer, without the bounce a key has
//     not got).
//   S: save the frame now shown.
//   Q or Esc (or closing the window): quit.
// A key's auto-repeat gives nothing more: a held R is one long press.
#pragma once

#include <cstdint>
#include <vector>

#include "input/button_source.hpp"
#include "input/debounce.hpp"

namespace probelight {

enum class WindowKey { kButton, kSave, kQuit, kOther };

struct WindowActions {
  std::vector<ButtonEvent::Kind> button;  // in order
  int saves = 0;
  bool quit = false;
  void add(const WindowActions& more);
};

class WindowKeys {
 public:
  explicit WindowKeys(double long_press_ms = DebounceSettings{}.long_press_ms);

  // A key went down (`down`) or up at `time_ns` (monotonic). `repeat`: the
  // window system's auto-repeat of a key held down.
  WindowActions onKey(WindowKey key, bool down, bool repeat, std::int64_t time_ns);
  // Time passing: a long press fires while the key is still held.
  WindowActions onTime(std::int64_t now_ns);
  // What the keys do, for the status bar: one line.
  static const char* help();

 private:
  WindowActions fromButton(const std::vector<ButtonEvent::Kind>& kinds) const;
  ButtonDebouncer button_;
};

}  // namespace probelight
