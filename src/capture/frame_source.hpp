// The camera seam. Frames arrive asynchronously from a capture thread into a
// small pool of buffers; the consumer borrows one (a FrameLease) and hands it
// back by dropping the lease, exactly as libcamera requests are re-queued.
#pragma once

#include <array>
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
  // The white balance's colour gains on red and blue (green 1), as
  // libcamera's ColourGains: 0 when unknown.
  double red_gain = 0.0;
  double blue_gain = 0.0;
  // Where the lens was focused (dioptres: 1 / distance in metres, 0 at
  // infinity; libcamera's LensPosition), within [0,
  // kMaxLensPositionDioptres]; nullopt when the camera has no lens control
  // or did not say.
  std::optional<double> lens_position_dioptres;
  std::string origin;           // file name or "sim:<index>", for messages
  std::optional<FrameTruth> truth;
};

// How a frame's pixels are stored. The camera formats are named as
// libcamera (and DRM) name them; their byte order in memory follows the
// DRM convention (little-endian words), so "RGB888" is B, G, R in memory.
enum class PixelLayout {
  kRgb8,      // tight R, G, B bytes in `rgb` (simulated RGB frames, image files, decoded MJPEG)
  kI420,      // YUV420: Y' plane, then Cb and Cr planes at half size both ways
  kNv12,      // NV12: Y' plane, then one plane of interleaved Cb, Cr at half size
  kYuyv,      // YUYV: one plane of Y'0 Cb Y'1 Cr per pixel pair (4:2:2, chroma sited on Y'0; USB webcams)
  kRgb888,    // RGB888: one plane, bytes B, G, R
  kBgr888,    // BGR888: one plane, bytes R, G, B (vimc's format)
  kXrgb8888,  // XRGB8888: one plane, bytes B, G, R, X
};

// The pixels of a frame in `planes` (every layout but kRgb8), as planes,
// each with its own row stride. I420 has three (Y', Cb, Cr), NV12 two (Y',
// then Cb Cr pairs; data[2] unused), the packed layouts one. 4:2:0 chroma
// is ceil(width/2) x ceil(height/2) samples, sited at the centre of each 2x2
// block. The planes are read in place: in a camera's mapped dmabuf, or in
// the source's own storage.
struct FramePlanes {
  const std::uint8_t* data[3] = {nullptr, nullptr, nullptr};
  int stride_bytes[3] = {0, 0, 0};
  YcbcrEncoding encoding;  // for the Y'CbCr layouts
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

// 3 for kI420, 2 for kNv12, 1 for the others.
int planeCount(PixelLayout layout);
// Y'CbCr-encoded: kI420, kNv12, kYuyv.
bool isYuv(PixelLayout layout);
// One plane of whole pixels: kYuyv (per pair), kRgb888, kBgr888, kXrgb8888.
bool isPacked(PixelLayout layout);
// Bytes a pixel takes in a packed layout's row (YUYV: 2); 0 for the others.
int packedBytesPerPixel(PixelLayout layout);
// Where R, G and B sit in a packed RGB pixel's bytes ({-1, -1, -1} otherwise).
std::array<int, 3> packedRgbByteOffsets(PixelLayout layout);
// libcamera's name for it ("YUV420", "BGR888", ...; "RGB" for kRgb8).
const char* layoutName(PixelLayout layout);

// One pooled buffer.
// 3 for kI420, 2 for kNv12, 1 for kRgb8.
int planeCount(PixelLayout layout);
bool isYuv(PixelLayout layout);

struct FrameBuffer {
  PixelLayout layout = PixelLayout::kRgb8;
  int width_px = 0;
  int height_px = 0;
  ImageRGB8 rgb;                          // kRgb8
  FramePlanes planes;                       // every layout but kRgb8
  std::vector<std::uint8_t> plane_storage;  // planes a source made itself
  // The luma the source computed on its own thread (off the render thread)
  // for kRgb8 and the packed layouts; I420 and NV12 need none: their Y'
  // plane is the luma.
  std::vector<std::uint8_t> luma_storage;
  FrameMetadata metadata;

  // What tag detection reads: the Y' plane, or the computed luma.
  LumaView luma() const;
  // Encoded R'G'B' codes of pixel (x, y) inside the frame, decoded from
  // Y'CbCr for YUV layouts (for the few hundred pixels the CPU reads, such
  // as the tag's white border; the GPU converts whole frames). It is the CPU
  // reference of the GPU's conversion: 4:2:0 chroma is read from the
  // pixel's block, YUYV's interpolated between co-sited samples as
  // GL_LINEAR does.
  glm::u8vec3 rgbAt(int x, int y) const;
  // The whole frame as 8-bit R'G'B' (a copy; decoded from Y'CbCr for YUV).
  ImageRGB8 toRgb() const;
  // Makes this an RGB frame of `rgb`'s size whose luma is computed from it.
  void finishRgb();
  // Makes this a kI420 or kNv12 frame of the given size in `plane_storage`
  // (tight rows) and returns the planes for the caller to fill.
  FramePlanes& allocateYuv420(PixelLayout layout, int width_px, int height_px, const YcbcrEncoding& encoding);
  // Makes this a frame of a packed layout of the given size in
  // `plane_storage` (tight rows) and returns its plane for the caller to
  // fill; then finishPacked() computes its luma.
  FramePlanes& allocatePacked(PixelLayout layout, int width_px, int height_px, const YcbcrEncoding& encoding);
  // The luma of a packed frame whose plane is filled (YUYV: its Y' bytes).
  void finishPacked();
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
  // The stream the source agreed on, once started ("BGR888 1920x1080
  // (stride 5760)"), for the log and the run report; empty when it has
  // nothing to say (replayed files).
  virtual std::string streamDescription() const { return ""; }
  // Whether the last start() failed because the source cannot do what the
  // settings ask (a pixel format or size the camera does not offer): a
  // configuration problem that trying again will not fix.
  virtual bool refusedItsSettings() const { return false; }
  // After a start(): one line where camera.yaml's lens position could not
  // be set as written (capture/lens_focus_choice.hpp), for the log; empty
  // otherwise and for sources with no camera (files, recordings).
  virtual std::string focusWarning() const { return ""; }
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
  // For produce(): waits `duration`, or less when the source is stopped
  // meanwhile (then false), so that a camera stalled on purpose can still
  // be stopped and re-opened.
  bool pauseUnlessStopped(std::chrono::milliseconds duration);

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
