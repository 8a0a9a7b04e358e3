#include "display/image_write_queue.hpp"

#include <algorithm>

namespace probelight {

ImageWriteQueue::ImageWriteQueue(WriteFunction write, int depth)
    : write_(std::move(write)), depth_(std::max(1, depth)), worker_([this] { run(); }) {}

ImageWriteQueue::~ImageWriteQueue() {
  {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return queue_.empty() && !busy_; });
    stopping_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

bool ImageWriteQueue::push(std::string path, ImageRGB8 image, std::string& error) {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return static_cast<int>(queue_.size()) < depth_ || !failure_.empty(); });
  if (!failure_.empty()) {
    error = failure_;
    return false;
  }
  queue_.emplace_back(std::move(path), std::move(image));
  lock.unlock();
  changed_.notify_all();
  return true;
}

bool ImageWriteQueue::finish(std::string& error) {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return queue_.empty() && !busy_; });
  if (failure_.empty()) return true;
  error = failure_;
  return false;
}

int ImageWriteQueue::written() const {
  std::lock_guard lock(mutex_);
  return written_;
}

void ImageWriteQueue::run() {
  std::unique_lock lock(mutex_);
  while (true) {
    changed_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stopping, nothing left
    auto [path, image] = std::move(queue_.front());
    queue_.pop_front();
    busy_ = true;
    lock.unlock();
    changed_.notify_all();  // a slot is free
    std::string why;
    const bool ok = write_(path, image, why);
    lock.lock();
    busy_ = false;
    if (ok)
      ++written_;
    else if (failure_.empty())
      failure_ = why.empty() ? "cannot write " + path : "cannot write " + why;
    changed_.notify_all();
  }
}

}  // namespace probelight
