// The camera seam. Frames arrive asynchronously from a capture thread into a
// small pool of buffers; the consumer borrows one (a FrameLease) and hands it
// back by dropping the lease, exactly as libcamera requests are re-queued.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/types.hpp"

namespace probelight {

struct FrameMetadata {
  std::uint64_t sequence = 0;
  std::int64_t timestamp_ns = 0;
  double exposure_us = 0.0;     // 0 when unknown
  double analogue_gain = 0.0;   // 0 when unknown
  std::string origin;           // file name or "sim:<index>", for messages
  std::optional<FrameTruth> truth;
};

// One pooled buffer. Sim and image sources fill `rgb`; the libcamera source
// (a later issue) will carry mapped YUV planes instead.
struct FrameBuffer {
  ImageRGB8 rgb;
  FrameMetadata metadata;
};

class FrameSource;

// Move-only loan of a filled buffer. Destroying it returns the buffer to its
// source's free list.
class FrameLease {
 public:
  FrameLease() = default;
  FrameLease(FrameBuffer* buffer, std::function<void(FrameBuffer*)> give_back)
      : buffer_(buffer), give_back_(std::move(give_back)) {}
  FrameLease(FrameLease&& other) noexcept { *this = std::move(other); }
  FrameLease& operator=(FrameLease&& other) noexcept {
    if (this != &other) {
      release();
      buffer_ = other.buffer_;
      give_back_ = std::move(other.give_back_);
      other.buffer_ = nullptr;
    }
    return *this;
  }
  FrameLease(const FrameLease&) = delete;
  FrameLease& operator=(const FrameLease&) = delete;
  ~FrameLease() { release(); }

  const FrameBuffer& operator*() const { return *buffer_; }
  const FrameBuffer* operator->() const { return buffer_; }
  explicit operator bool() const { return buffer_ != nullptr; }
  void release() {
    if (buffer_ && give_back_) give_back_(buffer_);
    buffer_ = nullptr;
  }

 private:
  FrameBuffer* buffer_ = nullptr;
  std::function<void(FrameBuffer*)> give_back_;
};

enum class FrameWait { kFrame, kTimeout, kEndOfStream, kError };

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // Starts capture. On failure returns false and sets `error` to one line a
  // user can act on.
  virtual bool start(std::string& error) = 0;
  virtual void stop() = 0;
  // Waits for the next completed frame.
  virtual FrameWait waitFrame(std::chrono::milliseconds timeout, FrameLease& lease) = 0;
  // Why the stream ended or failed (empty while healthy).
  virtual std::string lastError() const = 0;
  virtual std::string name() const = 0;
};

// Shared machinery for sources that make frames on a thread of their own:
// a fixed pool of buffers, a free list and a ready queue. The producer waits
// for a free buffer rather than dropping frames, so simulated runs are
// deterministic frame for frame.
class ThreadedFrameSource : public FrameSource {
 public:
  explicit ThreadedFrameSource(int pool_size = 3);
  ~ThreadedFrameSource() override;

  bool start(std::string& error) override;
  void stop() override;
  FrameWait waitFrame(std::chrono::milliseconds timeout, FrameLease& lease) override;
  std::string lastError() const override;

 protected:
  enum class Produced { kFrame, kEndOfStream, kError };
  // Called before the thread starts; may fail with a user-facing message.
  virtual bool prepare(std::string& error) { (void)error; return true; }
  // Fills `buffer` with frame number `index` (0-based). On kError, `error`
  // says why.
  virtual Produced produce(std::uint64_t index, FrameBuffer& buffer, std::string& error) = 0;

 private:
  void run();
  void giveBack(FrameBuffer* buffer);

  std::vector<std::unique_ptr<FrameBuffer>> pool_;
  std::deque<FrameBuffer*> free_;
  std::deque<FrameBuffer*> ready_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::thread thread_;
  bool stopping_ = false;
  bool ended_ = false;
  bool failed_ = false;
  std::string error_;
};

}  // namespace probelight
