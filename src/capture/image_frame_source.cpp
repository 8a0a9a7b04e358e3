#include "capture/image_frame_source.hpp"
#include "capture/rgb_image_io.hpp"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <system_error>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace probelight {

namespace {

bool hasImageExtension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
  static const char* const kExtensions[] = {".png", ".jpg", ".jpeg", ".bmp", ".tif",
                                            ".tiff", ".pgm", ".ppm", ".pnm", ".webp"};
  return std::any_of(std::begin(kExtensions), std::end(kExtensions), [&](const char* known) { return extension == known; });
}

std::vector<std::string> globRegularFiles(const std::string& pattern) {
  std::vector<std::string> files;
  glob_t matches{};
  if (::glob(pattern.c_str(), 0, nullptr, &matches) == 0) {
    for (std::size_t i = 0; i < matches.gl_pathc; ++i) {
      std::error_code ignored;
      if (std::filesystem::is_regular_file(matches.gl_pathv[i], ignored)) files.emplace_back(matches.gl_pathv[i]);
    }
  }
  ::globfree(&matches);
  return files;
}

}  // namespace

ImageFrameSource::ImageFrameSource(std::string folder_or_pattern, bool loop, int pool_size)
    : ThreadedFrameSource(pool_size), folder_or_pattern_(std::move(folder_or_pattern)), loop_(loop) {}

ImageFrameSource::~ImageFrameSource() {
  // The base destructor would join the thread only after this object's
  // members (which produce() uses) are gone.
  stop();
}

bool ImageFrameSource::prepare(std::string& error) {
  files_.clear();
  next_file_ = 0;
  std::error_code status;
  if (std::filesystem::is_directory(folder_or_pattern_, status)) {
    for (const auto& entry : std::filesystem::directory_iterator(folder_or_pattern_, status)) {
      std::error_code ignored;
      if (entry.is_regular_file(ignored) && hasImageExtension(entry.path())) files_.push_back(entry.path().string());
    }
    if (status) {
      error = "image source: cannot list folder '" + folder_or_pattern_ + "': " + status.message();
      return false;
    }
    if (files_.empty()) {
      error = "image source: folder '" + folder_or_pattern_ + "' has no image files (.png, .jpg, .bmp, .tif, ...)";
      return false;
    }
  } else {
    files_ = globRegularFiles(folder_or_pattern_);
    if (files_.empty()) {
      error = "image source: no files match '" + folder_or_pattern_ + "'";
      return false;
    }
  }
  std::sort(files_.begin(), files_.end());
  return true;
}

ThreadedFrameSource::Produced ImageFrameSource::produce(std::uint64_t index, FrameBuffer& buffer, std::string& error) {
  // Try each file at most once per call, so a folder of nothing but broken
  // files ends (or fails, when looping) instead of spinning.
  for (std::size_t attempts = 0; attempts < files_.size(); ++attempts) {
    if (next_file_ >= files_.size()) {
      if (!loop_ && frames_delivered_ > 0) return Produced::kEndOfStream;
      if (!loop_) break;
      next_file_ = 0;
    }
    const std::string& path = files_[next_file_++];
    std::string why;
    cv::Mat bgr = readImageFile(path, cv::IMREAD_COLOR, &why);
    if (bgr.empty()) {
      std::cerr << "probelight: warning: skipping '" << path << "': " << why << "\n";
      continue;
    }
    rgbFromBgr(bgr, buffer.rgb);
    buffer.finishRgb();
    buffer.metadata = FrameMetadata{};
    buffer.metadata.sequence = index;
    buffer.metadata.timestamp_ns =
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
    buffer.metadata.origin = path;
    ++frames_delivered_;
    return Produced::kFrame;
  }
  if (next_file_ >= files_.size() && !loop_ && frames_delivered_ > 0) return Produced::kEndOfStream;
  error = "image source: none of the " + std::to_string(files_.size()) + " files of '" + folder_or_pattern_ +
          "' could be decoded";
  return Produced::kError;
}

}  // namespace probelight
