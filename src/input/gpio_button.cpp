#include "input/gpio_button.hpp"

#include <ctime>

namespace probelight {

namespace {

std::int64_t monotonicNs() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

}  // namespace

GpioButton::GpioButton(GpioButtonSettings settings) : settings_(std::move(settings)) {}

GpioButton::~GpioButton() {
  stopping_ = true;
  if (thread_.joinable()) thread_.join();
}

std::string GpioButton::name() const { return "gpio " + settings_.chip + " line " + std::to_string(settings_.line); }

bool GpioButton::start(std::string& error) {
  if (!line_.open(settings_.chip, settings_.line, "probelight", error)) {
    error = "button: " + error;
    return false;
  }
  thread_ = std::thread([this] { readLoop(); });
  return true;
}

void GpioButton::readLoop() {
  // The logical value (active-low applied): 1 while the button is held.
  ButtonDebouncer debouncer(settings_.debounce, line_.level() == 1);
  auto deliver = [this](const std::vector<ButtonEvent::Kind>& kinds) {
    if (kinds.empty()) return;
    std::lock_guard<std::mutex> lock(mutex_);
    for (ButtonEvent::Kind kind : kinds) pending_.push_back({kind, std::chrono::steady_clock::now()});
  };
  while (!stopping_) {
    // Wake every 5 ms without an edge, so the debouncer can settle a level
    // and time a long press.
    const int ready = line_.waitEdge(5'000'000);
    if (ready < 0) break;  // the chip went away: no more presses
    if (ready == 0) {
      deliver(debouncer.onTime(monotonicNs()));
      continue;
    }
    line_.discardEdges();
    // The level after this edge, read back rather than taken from the
    // event's type: what active-low does to event types has changed between
    // kernels, the line's value has not.
    const int value = line_.level();
    if (value >= 0) deliver(debouncer.onLevel(monotonicNs(), value == 1));
  }
}

std::vector<ButtonEvent> GpioButton::poll() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<ButtonEvent> events;
  events.swap(pending_);
  return events;
}

}  // namespace probelight
