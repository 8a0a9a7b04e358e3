// The key button's input, cut into lines: bounded and safe to echo. Whatever
// writes to stdin or the FIFO may send a line without end or terminal escape
// sequences; neither may grow memory or reach the log as it came.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace probelight {

class KeyLineReader {
 public:
  // Longer lines are kept to this many bytes and marked cut: every command
  // ("r", "long", Enter) fits with room to spare.
  static constexpr std::size_t kMaxLineBytes = 256;

  struct Line {
    std::string text;  // at most kMaxLineBytes, without the '\n'
    bool cut = false;  // the line was longer; the rest was dropped
  };

  // The lines `bytes` completes ('\n' ends one).
  std::vector<Line> feed(const char* bytes, std::size_t count);
  // Bytes held for the line not yet ended (at most kMaxLineBytes).
  std::size_t pendingBytes() const { return partial_.text.size(); }

  // `text` as one log-safe phrase: printable ASCII kept, every other byte as
  // \xNN, at most 40 bytes of it and "..." after.
  static std::string printable(const std::string& text, bool cut = false);

 private:
  Line partial_;
};

}  // namespace probelight
