// Log lines with journald priority prefixes ("<3>" error, "<4>" warning,
// "<6>" info: sd-daemon(3)) when stderr goes to the journal, so that
// `journalctl -p warning -u probelight` shows what matters. Elsewhere (a
// terminal, a test) lines stay plain.
#pragma once

#include <iosfwd>
#include <memory>
#include <streambuf>
#include <string>

namespace probelight {

enum class LogPriority { kError = 3, kWarning = 4, kInfo = 6 };

// True when $JOURNAL_STREAM names stderr's device and inode (systemd sets it
// when it connects a service's stderr to the journal).
bool stderrIsJournal();

// "<N>" for the priority once journal prefixes are on, "" otherwise.
std::string logPrefix(LogPriority priority);

// Turns journal prefixes on for `stream` (std::cerr): every line that does
// not start with a "<N>" of its own gets "<6>". Keep the returned object
// alive while the stream is used; destroying it puts the old buffer back.
class JournalPrefixes {
 public:
  explicit JournalPrefixes(std::ostream& stream);
  ~JournalPrefixes();
  JournalPrefixes(const JournalPrefixes&) = delete;
  JournalPrefixes& operator=(const JournalPrefixes&) = delete;

 private:
  class LineBuffer;
  std::ostream& stream_;
  std::streambuf* original_;
  std::unique_ptr<LineBuffer> buffer_;
};

}  // namespace probelight
