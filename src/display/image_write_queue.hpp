// Writes images on a thread of its own, so that encoding one (a PNG of a
// 640x480 frame costs tens of milliseconds on a small CPU) never holds up
// the frames that follow. Bounded: push() waits while `depth` images are
// queued, so memory stays bounded and no frame is dropped. The first failed
// write is kept and reported by the next push() and by finish().
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

#include "core/types.hpp"

namespace probelight {

class ImageWriteQueue {
 public:
  // Writes `image` to `path`; false when it could not, with `error` saying
  // why (or left empty).
  using WriteFunction = std::function<bool(const std::string& path, const ImageRGB8& image, std::string& error)>;

  explicit ImageWriteQueue(WriteFunction write, int depth = 2);
  ~ImageWriteQueue();  // waits for the queued writes
  ImageWriteQueue(const ImageWriteQueue&) = delete;
  ImageWriteQueue& operator=(const ImageWriteQueue&) = delete;

  // Queues a write. False (with `error` naming the file) when an earlier
  // write failed; the image is then not queued.
  bool push(std::string path, ImageRGB8 image, std::string& error);
  // Waits until every queued write is done. False when any failed.
  bool finish(std::string& error);
  int written() const;

 private:
  void run();

  WriteFunction write_;
  const int depth_;
  std::deque<std::pair<std::string, ImageRGB8>> queue_;
  bool busy_ = false;  // the worker holds an image it took off the queue
  bool stopping_ = false;
  int written_ = 0;
  std::string failure_;  // "cannot write PATH" of the first failed write
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::thread worker_;
};

}  // namespace probelight
