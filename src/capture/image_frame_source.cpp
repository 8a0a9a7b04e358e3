#include "capture/image_frame_source.hpp"
#include "capture/rgb_image_io.hpp"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <optional>
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

// "ev-2" -> -2, "ev+1.5" -> 1.5; nullopt for any other name.
std::optional<double> exposureSetStops(const std::string& name) {
  if (name.size() < 3 || name.compare(0, 2, "ev") != 0) return std::nullopt;
  const char* begin = name.c_str() + 2;
  char* end = nullptr;
  const double stops = std::strtod(begin, &end);
  if (end == begin || *end != '\0' || !std::isfinite(stops) || std::abs(stops) > 16.0) return std::nullopt;
  return stops;
}

}  // namespace

ImageFrameSource::ImageFrameSource(std::string folder_or_pattern, bool loop, int pool_size)
    : ThreadedFrameSource(pool_size),
      folder_or_pattern_(std::move(folder_or_pattern)),
      loop_(loop),
      exposure_schedule_(pool_size) {}

std::vector<std::pair<double, std::string>> ImageFrameSource::exposureSets() const {
  std::lock_guard<std::mutex> lock(exposure_mutex_);
  return exposure_sets_;
}

bool ImageFrameSource::lockExposure(bool locked) {
  (void)locked;  // a replay's exposure does not drift: locked already
  std::lock_guard<std::mutex> lock(exposure_mutex_);
  return !exposure_sets_.empty();
}

bool ImageFrameSource::setExposureLadder(const std::vector<ManualExposure>& per_frame) {
  std::lock_guard<std::mutex> lock(exposure_mutex_);
  if (exposure_sets_.empty()) return false;
  exposure_schedule_.request(per_frame);
  return true;
}

void ImageFrameSource::handedOut(const FrameBuffer& frame) {
  std::lock_guard<std::mutex> lock(exposure_mutex_);
  exposure_schedule_.handedOut(frame.metadata.sequence);
}

ImageFrameSource::~ImageFrameSource() {
  // The base destructor would join the thread only after this object's
  // members (which produce() uses) are gone.
  stop();
}

bool ImageFrameSource::prepare(std::string& error) {
  files_.clear();
  next_file_ = 0;
  std::vector<std::pair<double, std::string>> sets;
  std::error_code status;
  if (std::filesystem::is_directory(folder_or_pattern_, status)) {
    for (const auto& entry : std::filesystem::directory_iterator(folder_or_pattern_, status)) {
      std::error_code ignored;
      if (entry.is_regular_file(ignored) && hasImageExtension(entry.path())) files_.push_back(entry.path().string());
      if (entry.is_directory(ignored))
        if (const auto stops = exposureSetStops(entry.path().filename().string()))
          sets.emplace_back(*stops, entry.path().string());
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
  std::sort(sets.begin(), sets.end());
  std::lock_guard<std::mutex> lock(exposure_mutex_);
  exposure_sets_ = std::move(sets);
  exposure_schedule_.clear();  // a restarted replay numbers its frames from 0 again
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
    const std::string& own_path = files_[next_file_++];
    // With exposure sets: the set nearest the exposure this frame is to be
    // taken at (its own files are stops 0).
    std::string path = own_path;
    double stops = 0.0;
    bool has_sets = false;
    {
      std::lock_guard<std::mutex> lock(exposure_mutex_);
      has_sets = !exposure_sets_.empty();
      if (const auto asked = exposure_schedule_.at(index)) {
        const double asked_stops = std::log2(asked->exposure_us * asked->analogue_gain / kReplayExposureUs);
        for (const auto& [set_stops, folder] : exposure_sets_)
          if (std::abs(set_stops - asked_stops) < std::abs(stops - asked_stops)) {
            stops = set_stops;
            path = (std::filesystem::path(folder) / std::filesystem::path(own_path).filename()).string();
          }
      }
    }
    std::string why;
    cv::Mat bgr = readImageFile(path, cv::IMREAD_COLOR, &why);
    if (bgr.empty() && path != own_path) {
      std::cerr << "probelight: warning: exposure set file '" << path << "': " << why << "; using '" << own_path
                << "' (stops 0)\n";
      path = own_path;
      stops = 0.0;
      bgr = readImageFile(path, cv::IMREAD_COLOR, &why);
    }
    if (bgr.empty()) {
      std::cerr << "probelight: warning: skipping '" << path << "': " << why << "\n";
      continue;
    }
    rgbFromBgr(bgr, buffer.rgb);
    buffer.finishRgb();
    buffer.metadata = FrameMetadata{};
    if (has_sets) {
      buffer.metadata.exposure_us = kReplayExposureUs * std::exp2(stops);
      buffer.metadata.analogue_gain = 1.0;
    }
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
