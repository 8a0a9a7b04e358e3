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

#include "capture/exposure_control.hpp"
#include "core/types.hpp"
#include "core/ycbcr.hpp"

namespace probelight {

struct FrameMetadata {
  std::uint64_t sequence = 0;
  std::int64_t timestamp_ns = 0;
  double exposure_us = 0.0;     // 0 when unknown
  double analogue_gain = 0.0;   // 0 when unknown
  std::string origin;           // file name or "sim:<index>", for messages
  std::optional<FrameTruth> truth;
};

enum class PixelLayout {
  kRgb8,  // `rgb`: 3 bytes per pixel (simulated RGB frames, image files)
  kI420,  // `yuv`: Y' plane, then Cb and Cr planes at half size (libcamera's YUV420)
  kNv12,  // `yuv`: Y' plane, then one plane of interleaved Cb, Cr at half size
};

// A Y'CbCr 4:2:0 picture as planes, each with its own row stride (chroma
// is ceil(width/2) x ceil(height/2) samples, sited at the centre of each 2x2
// block): I420 has three (Y', Cb, Cr), NV12 two (Y', then Cb Cr pairs;
// data[2] unused). The planes are read in place: in a camera's mapped
// dmabuf, or in the source's own storage.
struct YuvPlanes {
  const std::uint8_t* data[3] = {nullptr, nullptr, nullptr};
  int stride_bytes[3] = {0, 0, 0};
  YcbcrEncoding encoding;
  // The dmabuf behind each plane (-1: ordinary memory), for zero-copy import
  // as an EGLImage, and the plane's byte offset in it.
  int dmabuf_fd[3] = {-1, -1, -1};
  std::uint32_t dmabuf_offset[3] = {0, 0, 0};
  // Stable while the source lives: the same camera buffer has the same id,
  // so an importer can keep one EGLImage per buffer. 0: not a camera buffer.
  std::uint64_t buffer_id = 0;

  // Every plane of a `plane_count`-plane layout lives in a dmabuf.
  bool hasDmabuf(int plane_count) const {
    for (int p = 0; p < plane_count; ++p)
      if (dmabuf_fd[p] < 0) return false;
    return true;
  }
};

// One pooled buffer.
// 3 for kI420, 2 for kNv12, 1 for kRgb8.
int planeCount(PixelLayout layout);
bool isYuv(PixelLayout layout);

struct FrameBuffer {
  PixelLayout layout = PixelLayout::kRgb8;
  int width_px = 0;
  int height_px = 0;
  ImageRGB8 rgb;                          // kRgb8
  YuvPlanes yuv;                          // kI420, kNv12
  std::vector<std::uint8_t> yuv_storage;  // YUV planes a source made itself
  // kRgb8: the luma the source computed on its own thread (off the render
  // thread); YUV frames need none: the Y' plane is the luma.
  std::vector<std::uint8_t> luma_storage;
  FrameMetadata metadata;

  // What tag detection reads: the Y' plane, or the computed luma.
  LumaView luma() const;
  // Encoded R'G'B' codes of pixel (x, y) inside the frame, decoded from
  // Y'CbCr for YUV layouts (for the few hundred pixels the CPU reads, such
  // as the tag's white border; the GPU converts whole frames).
  glm::u8vec3 rgbAt(int x, int y) const;
  // The whole frame as 8-bit R'G'B' (a copy; decoded from Y'CbCr for YUV).
  ImageRGB8 toRgb() const;
  // Makes this an RGB frame of `rgb`'s size whose luma is computed from it.
  void finishRgb();
  // Makes this a kI420 or kNv12 frame of the given size in `yuv_storage`
  // (tight rows) and returns the planes for the caller to fill.
  YuvPlanes& allocateYuv420(PixelLayout layout, int width_px, int height_px, const YcbcrEncoding& encoding);
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

class FrameSource : public ExposureControl {
 public:
  // Starts capture. On failure returns false and sets `error` to one line a
  // user can act on.
  virtual bool start(std::string& error) = 0;
  virtual void stop() = 0;
  // Waits for the next completed frame.
  virtual FrameWait waitFrame(std::chrono::milliseconds timeout, FrameLease& lease) = 0;
  // Why the stream ended or failed (empty while healthy).
  virtual std::string lastError() const = 0;
  virtual std::string name() const = 0;
  // lockExposure, setExposureLadder and shortestExposureUs: ExposureControl's,
  // false or nothing where the source has no such controls.
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
  // Called on the consumer's thread as waitFrame hands `frame` out (sources
  // with exposure control move their schedule on: ExposureSchedule).
  virtual void handedOut(const FrameBuffer& frame) { (void)frame; }

 private:
  void run();
  void giveBack(FrameBuffer* buffer);

  std::vector<std::unique_ptr<FrameBuffer>> pool_;
  std::deque<FrameBuffer*> free_;
  std::deque<FrameBuffer*> ready_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::thread thread_;
  std::uint64_t next_index_ = 0;
  bool stopping_ = false;
  bool ended_ = false;
  bool failed_ = false;
  std::string error_;
};

}  // namespace probelight
