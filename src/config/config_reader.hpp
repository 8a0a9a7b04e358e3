// Typed, checked access to OpenCV FileStorage YAML configuration files.
//
// Every configuration file of probelight (camera.yaml, rig.yaml, the app's
// probelight.yaml) is read through ConfigReader so that every mistake a user
// can make is reported the same way: one line naming the file and the field.
//
//   config::ConfigReader file("rig.yaml");
//   double size_m = file.readDouble("tag_size", config::kRequired, config::Range::above(0.0));
//   auto sim = file.section("sim");               // nested map `sim: { env: studio }`
//   std::string env = sim.readString("env", "studio", {"studio", "parking"});
//   sim.rejectUnknownFields();
//   file.rejectUnknownFields();                   // typos such as `tag_sise` fail here
#pragma once

#include <cstddef>
#include <initializer_list>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <opencv2/core.hpp>

namespace probelight::config {

// What a file may be before OpenCV's parser is given it (ConfigReader).
constexpr std::size_t kMaxConfigFileBytes = std::size_t{16} << 20;
constexpr int kMaxConfigNestingDepth = 64;      // [ and { inside one another
constexpr int kMaxConfigIndentColumns = 1024;  // leading spaces of a line


// what() is always ONE line: "<file>: field '<name>': <problem>" or
// "<file>: <problem>" when the file itself cannot be read or parsed.
struct ConfigError : std::runtime_error {
  explicit ConfigError(const std::string& message);
};

// Passed as the default value of a field that must be present.
inline constexpr std::nullopt_t kRequired = std::nullopt;

// Allowed interval for a number. Aggregate-initialise for a closed interval
// ({0.0, 1.0}) or use the named constructors for open ends.
struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_inclusive = true;
  bool max_inclusive = true;

  static Range any() { return {}; }
  static Range atLeast(double min) { return {min}; }
  static Range above(double min) { return {min, std::numeric_limits<double>::infinity(), false}; }
  static Range atMost(double max) { return {-std::numeric_limits<double>::infinity(), max}; }
  static Range closed(double min, double max) { return {min, max}; }
  static Range openClosed(double min, double max) { return {min, max, false, true}; }

  bool contains(double value) const;
  std::string describe() const;  // e.g. "> 0", "in (0, 1]"
};

// Reads the fields of one map (the file's top level, or a nested section).
// Copies share the parsed file. Not thread-safe; configuration is read once.
class ConfigReader {
 public:
  // Opens and parses `path`. The "%YAML:1.0" header OpenCV insists on is
  // optional here, so hand-written files work. Throws ConfigError.
  explicit ConfigReader(const std::string& path);
  // Parses YAML text held in memory; `display_name` stands for the file name
  // in messages.
  static ConfigReader fromText(const std::string& yaml_text, const std::string& display_name);

  const std::string& path() const { return path_; }
  // Full dotted name of a field of this section, e.g. "sim.env".
  std::string fieldName(std::string_view name) const;
  bool has(std::string_view name) const;

  double readDouble(std::string_view name, std::optional<double> default_value = kRequired, Range range = Range::any());
  int readInt(std::string_view name, std::optional<int> default_value = kRequired, Range range = Range::any());
  // Accepts true/false, yes/no, on/off and 1/0 (OpenCV's YAML has no booleans).
  bool readBool(std::string_view name, std::optional<bool> default_value = kRequired);
  // `allowed` empty means any string.
  std::string readString(std::string_view name, std::optional<std::string> default_value = kRequired,
                         const std::vector<std::string>& allowed = {});
  // A sequence of exactly three numbers, each within `range_each`.
  glm::dvec3 readVec3(std::string_view name, std::optional<glm::dvec3> default_value = kRequired,
                      Range range_each = Range::any());
  // A list of numbers with min_count..max_count entries.
  std::vector<double> readDoubleList(std::string_view name, std::optional<std::vector<double>> default_value,
                                     std::size_t min_count, std::size_t max_count, Range range_each = Range::any());
  // Required matrix: an `!!opencv-matrix` node or a flat list of numbers
  // (filled row by row; a 1xN row when both sizes are kAnySize). Returned as
  // CV_64F; every element must be finite.
  static constexpr int kAnySize = -1;
  cv::Mat readMat(std::string_view name, int rows, int cols);

  // A nested map. When the section is absent an empty one is returned, so its
  // fields take their defaults (and required ones report "missing field
  // 'section.name'").
  ConfigReader section(std::string_view name);

  // Keys that may be present and are deliberately not read (e.g. what OpenCV's
  // calibration tools write beside the intrinsics).
  void ignoreFields(std::initializer_list<std::string_view> names);
  // Throws for the first key of this section that was neither read nor
  // ignored: catches typos.
  void rejectUnknownFields() const;

  // For checks that involve several fields (principal point inside the image).
  [[noreturn]] void fail(std::string_view name, const std::string& problem) const;

 private:
  struct Document;
  ConfigReader(std::shared_ptr<Document> document, cv::FileNode node, std::string prefix);
  // The node of `name`, marking it known; empty FileNode when absent.
  cv::FileNode lookup(std::string_view name);
  double toNumber(std::string_view name, const cv::FileNode& node) const;

  std::shared_ptr<Document> document_;
  cv::FileNode node_;
  std::string path_;
  std::string prefix_;  // "sim." for a section, "" at top level
  std::set<std::string, std::less<>> known_;
};

// Formats a number the way messages show it (shortest round-trip form).
std::string formatNumber(double value);

// Opens `path` for writing OpenCV FileStorage YAML whatever its extension.
// Throws ConfigError "<path>: cannot write file" on failure.
cv::FileStorage openYamlForWriting(const std::string& path);

}  // namespace probelight::config
