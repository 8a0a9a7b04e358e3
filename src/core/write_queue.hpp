// Writes files on a thread of its own, so that encoding or writing one (a
// PNG of a 640x480 frame costs tens of milliseconds on a small CPU; a raw
// camera frame is megabytes for the SD card) never holds up the frames that
// follow. Bounded: push() waits while `depth` items are queued, so memory
// stays bounded and no item is dropped. The first failed write is kept and
// reported by the next push() and by finish(); nothing is queued after it.
#pragma once

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

namespace probelight {

template <typename Item>
class WriteQueue {
 public:
  // Writes `item` to `path`; false when it could not, with `error` saying
  // why (or left empty).
  using WriteFunction = std::function<bool(const std::string& path, const Item& item, std::string& error)>;

  explicit WriteQueue(WriteFunction write, int depth = 2)
      : write_(std::move(write)), depth_(std::max(1, depth)), worker_([this] { run(); }) {}
  ~WriteQueue() {  // waits for the queued writes
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return queue_.empty() && !busy_; });
      stopping_ = true;
    }
    changed_.notify_all();
    worker_.join();
  }
  WriteQueue(const WriteQueue&) = delete;
  WriteQueue& operator=(const WriteQueue&) = delete;

  // Queues a write. False (with `error` naming the file) when an earlier
  // write failed; the item is then not queued.
  bool push(std::string path, Item item, std::string& error) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return static_cast<int>(queue_.size()) < depth_ || !failure_.empty(); });
    if (!failure_.empty()) {
      error = failure_;
      return false;
    }
    queue_.emplace_back(std::move(path), std::move(item));
    lock.unlock();
    changed_.notify_all();
    return true;
  }
  // Waits until every queued write is done. False when any failed.
  bool finish(std::string& error) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return queue_.empty() && !busy_; });
    if (failure_.empty()) return true;
    error = failure_;
    return false;
  }
  int written() const {
    std::lock_guard lock(mutex_);
    return written_;
  }

 private:
  void run() {
    std::unique_lock lock(mutex_);
    while (true) {
      changed_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stopping, nothing left
      auto [path, item] = std::move(queue_.front());
      queue_.pop_front();
      busy_ = true;
      lock.unlock();
      changed_.notify_all();  // a slot is free
      std::string why;
      const bool ok = write_(path, item, why);
      lock.lock();
      busy_ = false;
      if (ok)
        ++written_;
      else if (failure_.empty())
        failure_ = why.empty() ? "cannot write " + path : "cannot write " + why;
      changed_.notify_all();
    }
  }

  WriteFunction write_;
  const int depth_;
  std::deque<std::pair<std::string, Item>> queue_;
  bool busy_ = false;  // the worker holds an item it took off the queue
  bool stopping_ = false;
  int written_ = 0;
  std::string failure_;  // "cannot write PATH" of the first failed write
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::thread worker_;
};

}  // namespace probelight
