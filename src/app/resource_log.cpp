#include "app/resource_log.hpp"

#include <filesystem>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <sstream>
#include <system_error>

namespace probelight {

ProcessResources readProcessResources() {
  ProcessResources resources;
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) {
      std::istringstream fields(line.substr(6));
      long long kib = -1;
      if (fields >> kib) resources.rss_kib = kib;
    } else if (line.rfind("Threads:", 0) == 0) {
      std::istringstream fields(line.substr(8));
      int threads = -1;
      if (fields >> threads) resources.threads = threads;
    }
  }
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
  // An empty glibc heap in a running program means another allocator
  // serves malloc (a sanitizer's, or one preloaded): its figures are not
  // glibc's to give, so they stay unknown.
  const struct mallinfo2 heap = mallinfo2();
  if (heap.uordblks + heap.hblkhd > 0) {
    resources.heap_in_use_kib = static_cast<long long>((heap.uordblks + heap.hblkhd) / 1024);
    resources.heap_held_kib = static_cast<long long>((heap.arena + heap.hblkhd) / 1024);
  }
#endif
  std::error_code error;
  int count = 0;
  for (std::filesystem::directory_iterator it("/proc/self/fd", error), end; !error && it != end; it.increment(error))
    ++count;
  // The listing's own descriptor was open while it ran.
  if (!error) resources.open_fds = count > 0 ? count - 1 : 0;
  return resources;
}

bool ResourceLog::open(const std::string& path, std::string& error) {
  if (every_frames_ <= 0) return true;
  out_.open(path, std::ios::trunc);
  if (!out_) {
    error = path + ": cannot be written (output.resources_every_frames)";
    return false;
  }
  out_ << "frames,elapsed_s,rss_kib,open_fds,gl_objects,gl_textures,gl_framebuffers,gl_renderbuffers,gl_buffers,"
          "gl_programs,gl_shaders,threads,heap_in_use_kib,heap_held_kib\n";
  out_.flush();
  return true;
}

bool ResourceLog::due(std::uint64_t frames_done) const {
  if (every_frames_ <= 0 || !out_.is_open()) return false;
  return frames_done == 1 || frames_done % static_cast<std::uint64_t>(every_frames_) == 0;
}

void ResourceLog::write(std::uint64_t frames_done, double elapsed_s, const ProcessResources& process,
                        const gles::GlObjectCounts& gl) {
  out_ << frames_done << ',' << elapsed_s << ',' << process.rss_kib << ',' << process.open_fds << ',' << gl.total()
       << ',' << gl.textures << ',' << gl.framebuffers << ',' << gl.renderbuffers << ',' << gl.buffers << ','
       << gl.programs << ',' << gl.shaders << ',' << process.threads << ',' << process.heap_in_use_kib << ','
       << process.heap_held_kib << '\n';
  // Flushed: a soak reads it while the run goes on, and a killed run keeps it.
  out_.flush();
}

}  // namespace probelight
