// Shared by the fuzz targets (scripts/fuzz.sh): the loaders take paths, so
// each input is written to a file first, and what a target checks about a
// result it accepted.
#pragma once

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace probelight::fuzz {

// A folder of this process's own under /dev/shm (or the temp folder), made
// once; the input is rewritten there for every run.
inline const std::filesystem::path& workFolder() {
  static const std::filesystem::path folder = [] {
    std::filesystem::path base = std::filesystem::exists("/dev/shm") ? "/dev/shm" : std::filesystem::temp_directory_path();
    std::filesystem::path path = base / ("probelight-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(path);
    return path;
  }();
  return folder;
}

inline std::string writeInput(const std::uint8_t* data, std::size_t size, const std::string& name) {
  const std::string path = (workFolder() / name).string();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

// A broken promise about an accepted input: the fuzzer reports it as a crash
// with this message and keeps the input.
[[noreturn]] inline void fail(const char* what) {
  std::fprintf(stderr, "fuzz: %s\n", what);
  std::abort();
}

inline void require(bool promise_kept, const char* what) {
  if (!promise_kept) fail(what);
}

inline bool finite(double value) { return std::isfinite(value); }

// A loader's message is one line that names the file.
inline void requireOneLineNaming(const std::string& message, const std::string& path) {
  require(!message.empty(), "an empty error message");
  require(message.find('\n') == std::string::npos, "an error message of more than one line");
  require(message.find(path) != std::string::npos ||
              message.find(std::filesystem::path(path).filename().string()) != std::string::npos,
          "an error message that does not name the file");
}

}  // namespace probelight::fuzz
