#include "config/config_reader.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string_view>

namespace probelight::config {

namespace {

std::string collapseToOneLine(std::string text) {
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

const char* nodeKind(const cv::FileNode& node) {
  if (node.isInt()) return "an integer";
  if (node.isReal()) return "a number";
  if (node.isString()) return "text";
  if (node.isSeq()) return "a list";
  if (node.isMap()) return "a map";
  return "nothing";
}

std::string describeNode(const cv::FileNode& node) {
  if (node.isString()) {
    std::string text = static_cast<std::string>(node);
    // OpenCV's YAML reader keeps "text  # comment" as one string.
    if (text.find('#') != std::string::npos)
      return "text '" + text + "' (OpenCV's YAML has no end-of-line comments after text: put the comment on a line of its own)";
    return "text '" + text + "'";
  }
  if (node.isInt()) return "integer " + std::to_string(static_cast<int>(node));
  if (node.isReal()) return "number " + formatNumber(static_cast<double>(node));
  return nodeKind(node);
}

bool hasYamlHeader(const std::string& text) {
  std::size_t start = text.find_first_not_of(" \t\r\n");
  return start != std::string::npos && text.compare(start, 5, "%YAML") == 0;
}

// OpenCV reports parse errors as "... in function '<name>(<line>): <problem>'".
std::string describeParseError(const cv::Exception& e, int header_lines_added) {
  static const std::regex located(R"(\((\d+)\): ([^']*))");
  std::smatch match;
  if (std::regex_search(e.msg, match, located)) {
    int line = std::stoi(match[1].str()) - header_lines_added;
    return "malformed YAML at line " + std::to_string(std::max(line, 1)) + ": " + match[2].str();
  }
  return "malformed YAML: " + (e.err.empty() ? std::string(e.what()) : e.err);
}

void rejectDuplicateKeys(const cv::FileNode& map, const std::string& path, const std::string& prefix) {
  std::set<std::string> seen;
  for (const std::string& key : map.keys())
    if (!seen.insert(key).second) throw ConfigError(path + ": field '" + prefix + key + "': appears more than once");
}

}  // namespace

ConfigError::ConfigError(const std::string& message) : std::runtime_error(collapseToOneLine(message)) {}

std::string formatNumber(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[64];
  auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

cv::FileStorage openYamlForWriting(const std::string& path) {
  cv::FileStorage storage;
  try {
    storage.open(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    throw ConfigError(path + ": cannot write file (" + e.err + ")");
  }
  if (!storage.isOpened()) throw ConfigError(path + ": cannot write file (missing folder or no permission)");
  return storage;
}

bool Range::contains(double value) const {
  bool above_min = min_inclusive ? value >= min : value > min;
  bool below_max = max_inclusive ? value <= max : value < max;
  return above_min && below_max;
}

std::string Range::describe() const {
  bool has_min = std::isfinite(min);
  bool has_max = std::isfinite(max);
  if (has_min && has_max)
    return std::string("in ") + (min_inclusive ? "[" : "(") + formatNumber(min) + ", " + formatNumber(max) +
           (max_inclusive ? "]" : ")");
  if (has_min) return std::string(min_inclusive ? ">= " : "> ") + formatNumber(min);
  if (has_max) return std::string(max_inclusive ? "<= " : "< ") + formatNumber(max);
  return "any finite number";
}

struct ConfigReader::Document {
  cv::FileStorage storage;
};

ConfigReader::ConfigReader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot open file (missing or unreadable)");
  // Read at most one byte past the limit: a settings file is a few kB (an
  // OpenCV calibration with every view's points a few hundred), so more is
  // not one of ours, and need not be held in memory to say so.
  std::string text(kMaxConfigFileBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxConfigFileBytes)
    throw ConfigError(path + ": larger than " + std::to_string(kMaxConfigFileBytes >> 20) +
                      " MiB, not a probelight settings or calibration file");
  *this = fromText(text, path);
}

namespace {

// OpenCV reads an integer literal past 32 bits wrapped (4294967297 as 1) and
// one with a leading zero as octal (010 as 8), both silently (issue 15, D2,
// D3): such a token, as a whole (a run of letters, digits, '.', '+', '-'),
// is refused here with what OpenCV would have made of it.
std::optional<std::string> integerLiteralProblem(const std::string& token, int line) {
  std::size_t digits_from = (token[0] == '+' || token[0] == '-') ? 1 : 0;
  if (digits_from >= token.size()) return std::nullopt;
  const std::string digits = token.substr(digits_from);
  const std::string where = "line " + std::to_string(line) + ": ";
  if (digits.size() > 1 && digits[0] == '0' && (digits[1] == 'x' || digits[1] == 'X'))
    return where + token + " is hexadecimal, which is not read as written; write it in decimal";
  if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) return std::nullopt;
  if (digits.size() > 1 && digits[0] == '0')
    return where + token + " has a leading zero, which OpenCV reads as octal; write it without";
  if (digits.size() > 10 || std::stoll(digits) > 2147483647LL)
    return where + token + " does not fit in a 32-bit integer (OpenCV would wrap it)";
  return std::nullopt;
}

// OpenCV's YAML parser recurses once per nesting level with no limit, so a
// file nested 50,000 deep overflows the stack (issue 15, D1). Every file
// probelight reads is a few levels deep; the deepest flow nesting ([ and {)
// and the deepest indentation are checked before OpenCV sees the text, as
// are the integer literals it would misread (integerLiteralProblem, on
// each token). Empty when all is
// well, else the problem with its line number.
std::optional<std::string> textOpenCvWouldMisreadProblem(const std::string& text) {
  int depth = 0, line = 1, column = 0;
  bool in_comment = false, in_indent = true;
  char quote = 0;
  char previous = '\n';
  std::string token;
  auto isTokenChar = [](char c) {
    return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '.' || c == '+' ||
           c == '-' || c == '_';
  };
  for (std::size_t i = 0; i <= text.size(); ++i) {
    const char c = i < text.size() ? text[i] : '\n';
    // A token ends at any other character: check it as an integer literal.
    if (!in_comment && !quote && isTokenChar(c)) {
      token += c;
    } else if (!token.empty()) {
      // A key ("x1:") is no number; only values are read as integers.
      if (c != ':')
        if (std::optional<std::string> problem = integerLiteralProblem(token, line)) return problem;
      token.clear();
    }
    if (c == '\n') {
      ++line;
      column = 0;
      in_comment = false;
      in_indent = true;
      previous = c;
      continue;
    }
    if (in_indent && c == ' ') {
      if (++column > kMaxConfigIndentColumns)
        return "line " + std::to_string(line) + " is indented past column " + std::to_string(kMaxConfigIndentColumns);
      previous = c;
      continue;
    }
    in_indent = false;
    if (in_comment) continue;
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '#' && (previous == ' ' || previous == '\t' || previous == '\n')) {
      in_comment = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxConfigNestingDepth)
        return "nested deeper than " + std::to_string(kMaxConfigNestingDepth) + " levels at line " +
               std::to_string(line);
    } else if (c == ']' || c == '}') {
      depth = std::max(0, depth - 1);
    }
    previous = c;
  }
  return std::nullopt;
}

// OpenCV 4.6's YAML reader steps 3 characters past wherever its top-level
// collection ends, taking that for a "..." or "---" marker, and loops
// forever when it lands on a '-' that is not "---" (found by
// fuzz/probelight_yaml_fuzzer.cpp: "...\n-", then, in CI on 2026-12-07,
// "...-b" and "--- -m" with a shorter line after). It also reads only the
// first of several documents, silently. So every probelight file is one
// document whose top level can end only at the end of the file or at a
// "..." line, as OpenCV's own writer makes them:
//   - a line that starts with "---" or "..." is that marker alone, with at
//     most a comment after it (OpenCV takes the three characters as the
//     marker whatever follows them);
//   - "---" only before the first field; after "...", only blank lines and
//     comments;
//   - the top level starts at column 0: an indented top level ends at the
//     first line less indented, which is where the stepping goes wrong.
// Empty when all is well, else the problem with its line number.
std::optional<std::string> documentStructureProblem(const std::string& text) {
  bool content_seen = false;
  int line_number = 0, document_end_line = 0;
  for (std::size_t from = 0; from <= text.size();) {
    std::size_t to = text.find('\n', from);
    if (to == std::string::npos) to = text.size();
    std::string_view line(text.data() + from, to - from);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    ++line_number;
    from = to + 1;
    const std::string where = "line " + std::to_string(line_number) + ": ";
    const std::size_t first = line.find_first_not_of(" \t");
    const bool blank = first == std::string_view::npos || line[first] == '#';
    if (document_end_line != 0) {
      if (!blank)
        return where + "more after the end of the document ('...' at line " + std::to_string(document_end_line) +
               "); probelight reads one YAML document a file";
      continue;
    }
    const std::string_view marker = line.substr(0, 3);
    if (marker == "..." || marker == "---") {
      const std::size_t rest = line.find_first_not_of(" \t", 3);
      const bool stands_alone = rest == std::string_view::npos || line[rest] == '#';
      if (!stands_alone)
        return where + "text after '" + std::string(marker) +
               "' on its line; the marker stands alone, and the fields go on the lines below it";
      if (marker == "...") {
        document_end_line = line_number;
      } else if (content_seen) {
        return where + "a second YAML document begins ('---'); probelight reads one YAML document a file";
      }
    } else if (!blank && line[0] != '%') {
      if (!content_seen && first != 0)
        return where + "the top level is indented; its fields start at column 0";
      content_seen = true;
    }
  }
  return std::nullopt;
}

}  // namespace

ConfigReader ConfigReader::fromText(const std::string& yaml_text, const std::string& display_name) {
  if (yaml_text.find_first_not_of(" \t\r\n") == std::string::npos) throw ConfigError(display_name + ": file is empty");
  if (const std::optional<std::string> problem = textOpenCvWouldMisreadProblem(yaml_text))
    throw ConfigError(display_name + ": " + *problem + "; probelight's files are a few levels deep");
  if (const std::optional<std::string> problem = documentStructureProblem(yaml_text))
    throw ConfigError(display_name + ": " + *problem);
  // OpenCV refuses YAML without its "%YAML:1.0" first line; people writing
  // rig.yaml by hand should not have to know that.
  int header_lines_added = 0;
  std::string text = yaml_text;
  if (!hasYamlHeader(text)) {
    text = "%YAML:1.0\n" + text;
    header_lines_added = 1;
  }
  auto document = std::make_shared<Document>();
  try {
    document->storage.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    throw ConfigError(display_name + ": " + describeParseError(e, header_lines_added));
  } catch (const std::exception& e) {
    // OpenCV's parser can also fail past its own checks: a damaged file made
    // it throw std::length_error (found by fuzz/probelight_yaml_fuzzer.cpp).
    throw ConfigError(display_name + ": not a YAML file OpenCV can read (its parser failed: " + e.what() + ")");
  }
  if (!document->storage.isOpened()) throw ConfigError(display_name + ": not a YAML file OpenCV can read");
  cv::FileNode root = document->storage.root();
  if (!root.isMap()) throw ConfigError(display_name + ": expected a map of 'field: value' lines at the top level");
  rejectDuplicateKeys(root, display_name, "");
  ConfigReader reader(document, root, "");
  reader.path_ = display_name;
  return reader;
}

ConfigReader::ConfigReader(std::shared_ptr<Document> document, cv::FileNode node, std::string prefix)
    : document_(std::move(document)), node_(std::move(node)), prefix_(std::move(prefix)) {}

std::string ConfigReader::fieldName(std::string_view name) const { return prefix_ + std::string(name); }

void ConfigReader::fail(std::string_view name, const std::string& problem) const {
  throw ConfigError(path_ + ": field '" + fieldName(name) + "': " + problem);
}

bool ConfigReader::has(std::string_view name) const {
  if (!node_.isMap()) return false;
  cv::FileNode node = node_[std::string(name)];
  return !node.empty() && !node.isNone();
}

cv::FileNode ConfigReader::lookup(std::string_view name) {
  known_.emplace(name);
  if (!node_.isMap()) return cv::FileNode();
  return node_[std::string(name)];
}

double ConfigReader::toNumber(std::string_view name, const cv::FileNode& node) const {
  double value = 0.0;
  if (node.isInt())
    value = static_cast<int>(node);
  else if (node.isReal())
    value = static_cast<double>(node);
  else
    fail(name, "expected a number, got " + describeNode(node));
  if (!std::isfinite(value)) fail(name, "must be a finite number, got " + formatNumber(value));
  return value;
}

double ConfigReader::readDouble(std::string_view name, std::optional<double> default_value, Range range) {
  cv::FileNode node = lookup(name);
  if (node.empty() || node.isNone()) {
    if (default_value) return *default_value;
    fail(name, "missing (required number " + range.describe() + ")");
  }
  double value = toNumber(name, node);
  if (!range.contains(value)) fail(name, formatNumber(value) + " is out of range, must be " + range.describe());
  return value;
}

int ConfigReader::readInt(std::string_view name, std::optional<int> default_value, Range range) {
  cv::FileNode node = lookup(name);
  if (node.empty() || node.isNone()) {
    if (default_value) return *default_value;
    fail(name, "missing (required integer " + range.describe() + ")");
  }
  if (!node.isInt()) fail(name, "expected an integer, got " + describeNode(node));
  int value = static_cast<int>(node);
  if (!range.contains(value)) fail(name, std::to_string(value) + " is out of range, must be " + range.describe());
  return value;
}

bool ConfigReader::readBool(std::string_view name, std::optional<bool> default_value) {
  cv::FileNode node = lookup(name);
  if (node.empty() || node.isNone()) {
    if (default_value) return *default_value;
    fail(name, "missing (required true/false)");
  }
  if (node.isInt()) {
    int value = static_cast<int>(node);
    if (value == 0 || value == 1) return value == 1;
  } else if (node.isString()) {
    std::string text = static_cast<std::string>(node);
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
    if (text == "true" || text == "yes" || text == "on") return true;
    if (text == "false" || text == "no" || text == "off") return false;
  }
  fail(name, "expected true or false, got " + describeNode(node));
}

std::string ConfigReader::readString(std::string_view name, std::optional<std::string> default_value,
                                     const std::vector<std::string>& allowed) {
  cv::FileNode node = lookup(name);
  if (node.empty() || node.isNone()) {
    if (default_value) return *default_value;
    fail(name, "missing (required text)");
  }
  if (!node.isString()) fail(name, "expected text, got " + describeNode(node));
  std::string value = static_cast<std::string>(node);
  if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), value) == allowed.end()) {
    if (value.find('#') != std::string::npos) fail(name, "expected one of the allowed names, got " + describeNode(node));
    std::string choices;
    for (const std::string& choice : allowed) choices += (choices.empty() ? "" : ", ") + choice;
    fail(name, "'" + value + "' is not one of: " + choices);
  }
  return value;
}

std::vector<double> ConfigReader::readDoubleList(std::string_view name, std::optional<std::vector<double>> default_value,
                                                 std::size_t min_count, std::size_t max_count, Range range_each) {
  cv::FileNode node = lookup(name);
  if (node.empty() || node.isNone()) {
    if (default_value) return *default_value;
    fail(name, "missing (required list of numbers)");
  }
  std::string count_text = min_count == max_count ? std::to_string(min_count)
                                                  : std::to_string(min_count) + " to " + std::to_string(max_count);
  if (!node.isSeq()) fail(name, "expected a list of " + count_text + " numbers like [1, 2, 3], got " + describeNode(node));
  std::size_t count = node.size();
  if (count < min_count || count > max_count)
    fail(name, "expected " + count_text + " numbers, got " + std::to_string(count));
  std::vector<double> values;
  for (std::size_t i = 0; i < count; ++i) {
    cv::FileNode element = node[static_cast<int>(i)];
    std::string element_name = std::string(name) + "[" + std::to_string(i) + "]";
    double value = toNumber(element_name, element);
    if (!range_each.contains(value))
      fail(element_name, formatNumber(value) + " is out of range, must be " + range_each.describe());
    values.push_back(value);
  }
  return values;
}

glm::dvec3 ConfigReader::readVec3(std::string_view name, std::optional<glm::dvec3> default_value, Range range_each) {
  std::optional<std::vector<double>> fallback;
  if (default_value) fallback = std::vector<double>{default_value->x, default_value->y, default_value->z};
  std::vector<double> values = readDoubleList(name, fallback, 3, 3, range_each);
  return {values[0], values[1], values[2]};
}

cv::Mat ConfigReader::readMat(std::string_view name, int rows, int cols) {
  cv::FileNode node = lookup(name);
  std::string shape_text = (rows == kAnySize ? std::string("N") : std::to_string(rows)) + "x" +
                           (cols == kAnySize ? std::string("M") : std::to_string(cols));
  if (node.empty() || node.isNone()) fail(name, "missing (required " + shape_text + " matrix)");
  cv::Mat matrix;
  if (node.isSeq()) {
    // A flat list: its length must fit the fixed dimensions; with both free
    // it is a row vector (how people write distortion coefficients by hand).
    std::size_t count = node.size();
    std::size_t expected_min = 1, expected_max = std::numeric_limits<std::size_t>::max();
    if (rows != kAnySize && cols != kAnySize) expected_min = expected_max = static_cast<std::size_t>(rows * cols);
    std::vector<double> values = readDoubleList(name, kRequired, expected_min, expected_max);
    int known = rows != kAnySize ? rows : (cols != kAnySize ? cols : 0);
    if (known > 0 && count % static_cast<std::size_t>(known) != 0)
      fail(name, "expected a " + shape_text + " matrix, got a list of " + std::to_string(count) + " numbers");
    int matrix_rows = rows != kAnySize ? rows : (cols != kAnySize ? static_cast<int>(count) / cols : 1);
    matrix = cv::Mat(values, true).reshape(1, matrix_rows);
  } else if (node.isMap()) {
    if (node["rows"].empty() || node["cols"].empty() || node["data"].empty())
      fail(name, "expected an !!opencv-matrix with rows, cols, dt and data");
    // OpenCV reads the first of duplicate keys and ignores unknown ones;
    // either is a file that does not say what it seems to (issue 15, D9).
    std::set<std::string> keys;
    for (cv::FileNodeIterator it = node.begin(); it != node.end(); ++it) {
      const std::string key = (*it).name();
      if (key != "rows" && key != "cols" && key != "dt" && key != "data")
        fail(name, "unknown key '" + key + "' in the !!opencv-matrix (it holds rows, cols, dt and data)");
      if (!keys.insert(key).second) fail(name, "key '" + key + "' appears twice in the !!opencv-matrix");
    }
    // An integer type would round the values, u (8-bit) saturate them: a
    // focal length of 600 read as 255 gives a plausible, wrong pose (D8).
    const std::string type = node["dt"].isString() ? node["dt"].string() : std::string();
    if (type != "d" && type != "f")
      fail(name, "dt '" + type + "' would round or saturate the values; calibration matrices are dt: d (or f)");
    // cv::read allocates rows x cols before it looks at data: a matrix saying
    // 65536 x 65536 asked for 32 GB (found by fuzz/camera_yaml_fuzzer.cpp).
    // Its element count must be what data holds, which the file's size bounds.
    const cv::FileNode rows_node = node["rows"], cols_node = node["cols"], data_node = node["data"];
    if (!rows_node.isInt() || !cols_node.isInt() || !data_node.isSeq())
      fail(name, "the !!opencv-matrix's rows and cols must be whole numbers and its data a list");
    const long long declared_rows = static_cast<int>(rows_node), declared_cols = static_cast<int>(cols_node);
    if (declared_rows < 1 || declared_cols < 1 ||
        declared_rows * declared_cols != static_cast<long long>(data_node.size()))
      fail(name, "the !!opencv-matrix says " + std::to_string(declared_rows) + "x" + std::to_string(declared_cols) +
                     " but its data holds " + std::to_string(data_node.size()) + " numbers");
    try {
      cv::read(node, matrix, cv::Mat());
    } catch (const cv::Exception& e) {
      fail(name, "not a valid !!opencv-matrix (" + e.err + ")");
    }
    if (matrix.empty() || matrix.channels() != 1) fail(name, "not a valid single-channel !!opencv-matrix");
    matrix.convertTo(matrix, CV_64F);
  } else {
    fail(name, "expected a " + shape_text + " !!opencv-matrix, got " + describeNode(node));
  }
  if ((rows != kAnySize && matrix.rows != rows) || (cols != kAnySize && matrix.cols != cols))
    fail(name, "expected a " + shape_text + " matrix, got " + std::to_string(matrix.rows) + "x" +
                   std::to_string(matrix.cols));
  for (int r = 0; r < matrix.rows; ++r)
    for (int c = 0; c < matrix.cols; ++c)
      if (!std::isfinite(matrix.at<double>(r, c)))
        fail(name, "element (" + std::to_string(r) + ", " + std::to_string(c) + ") is " +
                       formatNumber(matrix.at<double>(r, c)) + ", must be finite");
  return matrix;
}

ConfigReader ConfigReader::section(std::string_view name) {
  cv::FileNode node = lookup(name);
  if (!node.empty() && !node.isNone()) {
    if (!node.isMap()) fail(name, "expected a section (a map of fields), got " + describeNode(node));
    rejectDuplicateKeys(node, path_, fieldName(name) + ".");
  } else {
    node = cv::FileNode();
  }
  ConfigReader child(document_, node, fieldName(name) + ".");
  child.path_ = path_;
  return child;
}

void ConfigReader::ignoreFields(std::initializer_list<std::string_view> names) {
  for (std::string_view name : names) known_.emplace(name);
}

void ConfigReader::rejectUnknownFields() const {
  if (!node_.isMap()) return;
  for (const std::string& key : node_.keys()) {
    if (known_.count(key)) continue;
    std::string known_list;
    for (const std::string& known : known_) known_list += (known_list.empty() ? "" : ", ") + known;
    fail(key, "unknown field (known fields: " + known_list + ")");
  }
}

}  // namespace probelight::config
