#include "input/gpio_button.hpp"

#include <cerrno>
#include <cstring>
#include <ctime>

#include <gpiod.h>

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
  if (line_) gpiod_line_release(line_);
  if (chip_) gpiod_chip_close(chip_);
}

std::string GpioButton::name() const { return "gpio " + settings_.chip + " line " + std::to_string(settings_.line); }

bool GpioButton::start(std::string& error) {
  chip_ = gpiod_chip_open_lookup(settings_.chip.c_str());
  if (!chip_) {
    error = "button: GPIO chip '" + settings_.chip + "' not found (" + std::strerror(errno) +
            "): is this a board with GPIO, and may this user open /dev/gpiochip* (group gpio)?";
    return false;
  }
  line_ = gpiod_chip_get_line(chip_, static_cast<unsigned>(settings_.line));
  if (!line_) {
    error = "button: " + settings_.chip + " has no line " + std::to_string(settings_.line) + " (" +
            std::to_string(gpiod_chip_num_lines(chip_)) + " lines)";
    return false;
  }
  gpiod_line_request_config config{};
  config.consumer = "probelight";
  config.request_type = GPIOD_LINE_REQUEST_EVENT_BOTH_EDGES;
  config.flags = GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW | GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_UP;
  if (gpiod_line_request(line_, &config, 0) != 0) {
    error = "button: cannot request " + settings_.chip + " line " + std::to_string(settings_.line) + " (" +
            std::strerror(errno) + "): another program may hold it";
    line_ = nullptr;
    return false;
  }
  thread_ = std::thread([this] { readLoop(); });
  return true;
}

void GpioButton::readLoop() {
  // The logical value (active-low applied): 1 while the button is held.
  ButtonDebouncer debouncer(settings_.debounce, gpiod_line_get_value(line_) == 1);
  auto deliver = [this](const std::vector<ButtonEvent::Kind>& kinds) {
    if (kinds.empty()) return;
    std::lock_guard<std::mutex> lock(mutex_);
    for (ButtonEvent::Kind kind : kinds) pending_.push_back({kind, std::chrono::steady_clock::now()});
  };
  while (!stopping_) {
    // Wake every 5 ms without an edge, so the debouncer can settle a level
    // and time a long press.
    const timespec timeout{0, 5'000'000};
    const int ready = gpiod_line_event_wait(line_, &timeout);
    if (ready < 0) break;  // the chip went away: no more presses
    if (ready == 0) {
      deliver(debouncer.onTime(monotonicNs()));
      continue;
    }
    gpiod_line_event event{};
    if (gpiod_line_event_read(line_, &event) != 0) continue;
    // The level after this edge, read back rather than taken from the
    // event's type: what active-low does to event types has changed between
    // kernels, the line's value has not.
    const int value = gpiod_line_get_value(line_);
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
