// What a long run holds, sampled every N frames into a CSV, so that a leak
// shows as a column that grows: the process's resident memory, threads and
// open file descriptors (from /proc/self), the heap as the allocator sees it
// (glibc's mallinfo2: what the program holds, and what the allocator keeps
// from the system for it), and the GL objects the driver holds for it
// (gles::countLiveGlObjects). The two heap figures tell a leak (in use
// grows) from allocator retention (only the held figure grows).
// probelight.yaml's output.resources_every_frames; scripts/soak.sh reads the
// file.
#pragma once

#include <cstdint>
#include <fstream>
#include <string>

#include "gles/gl_objects.hpp"

namespace probelight {

struct ProcessResources {
  long long rss_kib = -1;  // VmRSS; -1 where /proc/self/status cannot be read
  int open_fds = -1;       // entries of /proc/self/fd; -1 where it cannot be listed
  int threads = -1;        // Threads: of /proc/self/status
  // mallinfo2, over all arenas: the bytes malloc has handed out and not had
  // back (uordblks + hblkhd), and the bytes it holds from the system for the
  // heap (arena + hblkhd); -1 without glibc's allocator (a sanitizer's).
  long long heap_in_use_kib = -1;
  long long heap_held_kib = -1;
};
ProcessResources readProcessResources();

class ResourceLog {
 public:
  // every_frames 0: off (open() writes nothing).
  explicit ResourceLog(int every_frames) : every_frames_(every_frames) {}
  // Creates `path` with its header. False, with a one-line reason, when it
  // cannot be written.
  bool open(const std::string& path, std::string& error);
  // Whether a sample is due after `frames_done` frames: the first frame, and
  // every `every_frames` after it.
  bool due(std::uint64_t frames_done) const;
  // One row; `gl` from the render thread (countLiveGlObjects needs the context).
  void write(std::uint64_t frames_done, double elapsed_s, const ProcessResources& process, const gles::GlObjectCounts& gl);

 private:
  int every_frames_;
  std::ofstream out_;
};

}  // namespace probelight
