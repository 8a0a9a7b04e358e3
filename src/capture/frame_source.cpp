#include "capture/frame_source.hpp"

namespace probelight {

ThreadedFrameSource::ThreadedFrameSource(int pool_size) {
  for (int i = 0; i < pool_size; ++i) {
    pool_.push_back(std::make_unique<FrameBuffer>());
    free_.push_back(pool_.back().get());
  }
}

ThreadedFrameSource::~ThreadedFrameSource() {
  // Derived destructors must call stop() themselves: produce() is theirs.
  stop();
}

bool ThreadedFrameSource::start(std::string& error) {
  if (thread_.joinable()) return true;
  if (!prepare(error)) return false;
  stopping_ = false;
  thread_ = std::thread([this] { run(); });
  return true;
}

void ThreadedFrameSource::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ThreadedFrameSource::run() {
  for (std::uint64_t index = 0;; ++index) {
    FrameBuffer* buffer = nullptr;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [&] { return stopping_ || !free_.empty(); });
      if (stopping_) return;
      buffer = free_.front();
      free_.pop_front();
    }
    std::string error;
    Produced produced = produce(index, *buffer, error);
    std::lock_guard<std::mutex> lock(mutex_);
    if (produced == Produced::kFrame) {
      ready_.push_back(buffer);
    } else {
      free_.push_back(buffer);
      ended_ = true;
      failed_ = produced == Produced::kError;
      error_ = error;
      changed_.notify_all();
      return;
    }
    changed_.notify_all();
  }
}

FrameWait ThreadedFrameSource::waitFrame(std::chrono::milliseconds timeout, FrameLease& lease) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (!changed_.wait_for(lock, timeout, [&] { return !ready_.empty() || ended_; })) return FrameWait::kTimeout;
  if (!ready_.empty()) {
    FrameBuffer* buffer = ready_.front();
    ready_.pop_front();
    lock.unlock();
    lease = FrameLease(buffer, [this](FrameBuffer* b) { giveBack(b); });
    return FrameWait::kFrame;
  }
  return failed_ ? FrameWait::kError : FrameWait::kEndOfStream;
}

void ThreadedFrameSource::giveBack(FrameBuffer* buffer) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(buffer);
  }
  changed_.notify_all();
}

std::string ThreadedFrameSource::lastError() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

}  // namespace probelight
