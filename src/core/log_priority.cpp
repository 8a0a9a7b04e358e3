#include "core/log_priority.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <ostream>

namespace probelight {

namespace {
std::atomic<bool> g_prefixes_on{false};
}  // namespace

bool stderrIsJournal() {
  const char* value = std::getenv("JOURNAL_STREAM");
  if (!value) return false;
  unsigned long long device = 0, inode = 0;
  if (std::sscanf(value, "%llu:%llu", &device, &inode) != 2) return false;
  struct stat status {};
  if (::fstat(STDERR_FILENO, &status) != 0) return false;
  return static_cast<unsigned long long>(status.st_dev) == device &&
         static_cast<unsigned long long>(status.st_ino) == inode;
}

std::string logPrefix(LogPriority priority) {
  if (!g_prefixes_on) return "";
  return "<" + std::to_string(static_cast<int>(priority)) + ">";
}

// Collects a line, then writes it with "<6>" in front unless it has a
// priority of its own.
class JournalPrefixes::LineBuffer final : public std::streambuf {
 public:
  explicit LineBuffer(std::streambuf* target) : target_(target) {}

 protected:
  int_type overflow(int_type ch) override {
    if (traits_type::eq_int_type(ch, traits_type::eof())) return traits_type::not_eof(ch);
    line_.push_back(traits_type::to_char_type(ch));
    if (ch == '\n') flushLine();
    return ch;
  }
  // std::cerr flushes after every <<: a line is written only when complete,
  // so that its prefix comes once, before the whole line.
  int sync() override { return target_->pubsync(); }

 public:
  void finish() {
    if (!line_.empty()) flushLine();
    target_->pubsync();
  }

 private:
  void flushLine() {
    const bool has_priority = line_.size() >= 3 && line_[0] == '<' && line_[1] >= '0' && line_[1] <= '7' && line_[2] == '>';
    if (!has_priority) target_->sputn("<6>", 3);
    target_->sputn(line_.data(), static_cast<std::streamsize>(line_.size()));
    line_.clear();
  }
  std::streambuf* target_;
  std::string line_;
};

JournalPrefixes::JournalPrefixes(std::ostream& stream)
    : stream_(stream), original_(stream.rdbuf()), buffer_(std::make_unique<LineBuffer>(original_)) {
  stream_.rdbuf(buffer_.get());
  g_prefixes_on = true;
}

JournalPrefixes::~JournalPrefixes() {
  stream_.flush();
  buffer_->finish();  // a last line without its newline
  stream_.rdbuf(original_);
  g_prefixes_on = false;
}

}  // namespace probelight
