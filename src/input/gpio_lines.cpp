#include "input/gpio_lines.hpp"

#include <cctype>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>

#include <gpiod.h>

namespace probelight {

std::optional<std::string> gpioChipPath(const std::string& chip) {
  if (chip.empty()) return std::nullopt;
  if (chip.front() == '/') return chip;
  bool digits = true;
  for (const char c : chip) digits = digits && std::isdigit(static_cast<unsigned char>(c));
  if (digits) return "/dev/gpiochip" + chip;
  if (chip.rfind("gpiochip", 0) == 0) return "/dev/" + chip;
  return std::nullopt;
}

namespace {

std::string notFound(const std::string& chip) {
  return "GPIO chip '" + chip + "' not found (" + std::strerror(errno) +
         "): is this a board with GPIO, and may this user open /dev/gpiochip* (group gpio)?";
}

std::string busy(const std::string& chip, int line, const char* as) {
  return "cannot request " + chip + " line " + std::to_string(line) + " as " + as + " (" + std::strerror(errno) +
         "): another program may hold it";
}

}  // namespace

#ifdef PROBELIGHT_LIBGPIOD_V2
// ---------------------------------------------------------------------------
// v2: chips by path, requests built from settings and configs.

struct GpioHandles {
  gpiod_chip* chip = nullptr;
  gpiod_line_request* request = nullptr;
  gpiod_edge_event_buffer* events = nullptr;
  ~GpioHandles() {
    if (events) gpiod_edge_event_buffer_free(events);
    if (request) gpiod_line_request_release(request);
    if (chip) gpiod_chip_close(chip);
  }
};

std::string gpioLibraryDescription() { return std::string("libgpiod ") + gpiod_api_version() + " (v2 API)"; }

namespace {

// v2 opens chips by path only: a label is looked up among /dev/gpiochip*.
gpiod_chip* openChip(const std::string& chip) {
  if (const std::optional<std::string> path = gpioChipPath(chip)) return gpiod_chip_open(path->c_str());
  std::error_code ignored;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", ignored)) {
    const std::string path = entry.path().string();
    if (entry.path().filename().string().rfind("gpiochip", 0) != 0 || !gpiod_is_gpiochip_device(path.c_str())) continue;
    gpiod_chip* candidate = gpiod_chip_open(path.c_str());
    if (!candidate) continue;
    gpiod_chip_info* info = gpiod_chip_get_info(candidate);
    const bool match = info && chip == gpiod_chip_info_get_label(info);
    if (info) gpiod_chip_info_free(info);
    if (match) return candidate;
    gpiod_chip_close(candidate);
  }
  errno = ENOENT;
  return nullptr;
}

bool request(GpioHandles& handles, const std::string& chip, int line, gpiod_line_settings* settings,
             const std::string& consumer, const char* as, std::string& error) {
  handles.chip = openChip(chip);
  if (!handles.chip) {
    error = notFound(chip);
    return false;
  }
  gpiod_chip_info* info = gpiod_chip_get_info(handles.chip);
  const std::size_t line_count = info ? gpiod_chip_info_get_num_lines(info) : 0;
  if (info) gpiod_chip_info_free(info);
  if (line < 0 || static_cast<std::size_t>(line) >= line_count) {
    error = chip + " has no line " + std::to_string(line) + " (" + std::to_string(line_count) + " lines)";
    return false;
  }
  gpiod_line_config* line_config = gpiod_line_config_new();
  gpiod_request_config* request_config = gpiod_request_config_new();
  const unsigned offset = static_cast<unsigned>(line);
  if (line_config && request_config && gpiod_line_config_add_line_settings(line_config, &offset, 1, settings) == 0) {
    gpiod_request_config_set_consumer(request_config, consumer.c_str());
    handles.request = gpiod_chip_request_lines(handles.chip, request_config, line_config);
  }
  if (line_config) gpiod_line_config_free(line_config);
  if (request_config) gpiod_request_config_free(request_config);
  if (!handles.request) {
    error = busy(chip, line, as);
    return false;
  }
  return true;
}

}  // namespace

GpioInputLine::GpioInputLine() : handles_(new GpioHandles) {}
GpioInputLine::~GpioInputLine() { delete handles_; }

bool GpioInputLine::open(const std::string& chip, int line, const std::string& consumer, std::string& error) {
  gpiod_line_settings* settings = gpiod_line_settings_new();
  if (!settings) {
    error = "out of memory";
    return false;
  }
  gpiod_line_settings_set_direction(settings, GPIOD_LINE_DIRECTION_INPUT);
  gpiod_line_settings_set_edge_detection(settings, GPIOD_LINE_EDGE_BOTH);
  gpiod_line_settings_set_bias(settings, GPIOD_LINE_BIAS_PULL_UP);
  gpiod_line_settings_set_active_low(settings, true);
  const bool ok = request(*handles_, chip, line, settings, consumer, "an input", error);
  gpiod_line_settings_free(settings);
  if (!ok) return false;
  handles_->events = gpiod_edge_event_buffer_new(16);
  offset_ = static_cast<unsigned>(line);
  return handles_->events != nullptr;
}

int GpioInputLine::waitEdge(std::int64_t timeout_ns) {
  return gpiod_line_request_wait_edge_events(handles_->request, timeout_ns);
}

void GpioInputLine::discardEdges() { gpiod_line_request_read_edge_events(handles_->request, handles_->events, 16); }

int GpioInputLine::level() {
  const gpiod_line_value value = gpiod_line_request_get_value(handles_->request, offset_);
  return value == GPIOD_LINE_VALUE_ERROR ? -1 : value == GPIOD_LINE_VALUE_ACTIVE ? 1 : 0;
}

GpioOutputLine::GpioOutputLine() : handles_(new GpioHandles) {}
GpioOutputLine::~GpioOutputLine() {
  if (handles_->request) gpiod_line_request_set_value(handles_->request, offset_, GPIOD_LINE_VALUE_INACTIVE);
  delete handles_;
}

bool GpioOutputLine::open(const std::string& chip, int line, bool active_low, const std::string& consumer,
                          std::string& error) {
  gpiod_line_settings* settings = gpiod_line_settings_new();
  if (!settings) {
    error = "out of memory";
    return false;
  }
  gpiod_line_settings_set_direction(settings, GPIOD_LINE_DIRECTION_OUTPUT);
  gpiod_line_settings_set_active_low(settings, active_low);
  gpiod_line_settings_set_output_value(settings, GPIOD_LINE_VALUE_INACTIVE);
  const bool ok = request(*handles_, chip, line, settings, consumer, "an output", error);
  gpiod_line_settings_free(settings);
  offset_ = static_cast<unsigned>(line);
  return ok;
}

bool GpioOutputLine::isOpen() const { return handles_->request != nullptr; }

bool GpioOutputLine::set(bool active) {
  return handles_->request && gpiod_line_request_set_value(handles_->request, offset_,
                                                           active ? GPIOD_LINE_VALUE_ACTIVE : GPIOD_LINE_VALUE_INACTIVE) == 0;
}

#else
// ---------------------------------------------------------------------------
// v1: gpiod_chip_open_lookup takes names, numbers, paths and labels.

struct GpioHandles {
  gpiod_chip* chip = nullptr;
  gpiod_line* line = nullptr;  // requested when set
  ~GpioHandles() {
    if (line) gpiod_line_release(line);
    if (chip) gpiod_chip_close(chip);
  }
};

std::string gpioLibraryDescription() { return std::string("libgpiod ") + gpiod_version_string() + " (v1 API)"; }

namespace {

bool request(GpioHandles& handles, const std::string& chip, int line, int request_type, int flags,
             const std::string& consumer, const char* as, std::string& error) {
  handles.chip = gpiod_chip_open_lookup(chip.c_str());
  if (!handles.chip) {
    error = notFound(chip);
    return false;
  }
  gpiod_line* found = line >= 0 ? gpiod_chip_get_line(handles.chip, static_cast<unsigned>(line)) : nullptr;
  if (!found) {
    error = chip + " has no line " + std::to_string(line) + " (" + std::to_string(gpiod_chip_num_lines(handles.chip)) +
            " lines)";
    return false;
  }
  gpiod_line_request_config config{};
  config.consumer = consumer.c_str();
  config.request_type = request_type;
  config.flags = flags;
  if (gpiod_line_request(found, &config, 0) != 0) {
    error = busy(chip, line, as);
    return false;
  }
  handles.line = found;
  return true;
}

}  // namespace

GpioInputLine::GpioInputLine() : handles_(new GpioHandles) {}
GpioInputLine::~GpioInputLine() { delete handles_; }

bool GpioInputLine::open(const std::string& chip, int line, const std::string& consumer, std::string& error) {
  offset_ = static_cast<unsigned>(line);
  return request(*handles_, chip, line, GPIOD_LINE_REQUEST_EVENT_BOTH_EDGES,
                 GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW | GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_UP, consumer, "an input", error);
}

int GpioInputLine::waitEdge(std::int64_t timeout_ns) {
  const timespec timeout{static_cast<time_t>(timeout_ns / 1'000'000'000), static_cast<long>(timeout_ns % 1'000'000'000)};
  return gpiod_line_event_wait(handles_->line, &timeout);
}

void GpioInputLine::discardEdges() {
  gpiod_line_event event{};
  (void)gpiod_line_event_read(handles_->line, &event);
}

int GpioInputLine::level() { return gpiod_line_get_value(handles_->line); }

GpioOutputLine::GpioOutputLine() : handles_(new GpioHandles) {}
GpioOutputLine::~GpioOutputLine() {
  if (handles_->line) gpiod_line_set_value(handles_->line, 0);
  delete handles_;
}

bool GpioOutputLine::open(const std::string& chip, int line, bool active_low, const std::string& consumer,
                          std::string& error) {
  offset_ = static_cast<unsigned>(line);
  return request(*handles_, chip, line, GPIOD_LINE_REQUEST_DIRECTION_OUTPUT,
                 active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0, consumer, "an output", error);
}

bool GpioOutputLine::isOpen() const { return handles_->line != nullptr; }

bool GpioOutputLine::set(bool active) { return handles_->line && gpiod_line_set_value(handles_->line, active ? 1 : 0) == 0; }

#endif

}  // namespace probelight
