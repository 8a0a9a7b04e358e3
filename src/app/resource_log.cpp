#include "app/resource_log.hpp"

#include <filesystem>
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
      break;
    }
  }
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
          "gl_programs,gl_shaders\n";
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
       << gl.programs << ',' << gl.shaders << '\n';
  // Flushed: a soak reads it while the run goes on, and a killed run keeps it.
  out_.flush();
}

}  // namespace probelight
