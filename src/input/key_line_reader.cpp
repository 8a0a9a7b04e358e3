#include "input/key_line_reader.hpp"

#include <cstdio>

namespace probelight {

std::vector<KeyLineReader::Line> KeyLineReader::feed(const char* bytes, std::size_t count) {
  std::vector<Line> lines;
  for (std::size_t i = 0; i < count; ++i) {
    if (bytes[i] == '\n') {
      lines.push_back(std::move(partial_));
      partial_ = Line{};
    } else if (partial_.text.size() < kMaxLineBytes) {
      partial_.text.push_back(bytes[i]);
    } else {
      partial_.cut = true;
    }
  }
  return lines;
}

std::string KeyLineReader::printable(const std::string& text, bool cut) {
  constexpr std::size_t kShownBytes = 40;
  std::string shown;
  for (std::size_t i = 0; i < text.size() && i < kShownBytes; ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if (byte >= 0x20 && byte < 0x7F && byte != '\\') {
      shown.push_back(static_cast<char>(byte));
    } else {
      char escaped[5];
      std::snprintf(escaped, sizeof escaped, "\\x%02X", byte);
      shown += escaped;
    }
  }
  if (cut || text.size() > kShownBytes) shown += "...";
  return shown;
}

}  // namespace probelight
