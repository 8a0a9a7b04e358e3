#include "capture/frame_source.hpp"

#include <algorithm>
#include <cmath>

namespace probelight {

int planeCount(PixelLayout layout) {
  return layout == PixelLayout::kI420 ? 3 : layout == PixelLayout::kNv12 ? 2 : 1;
}

bool isYuv(PixelLayout layout) {
  return layout == PixelLayout::kI420 || layout == PixelLayout::kNv12 || layout == PixelLayout::kYuyv;
}

bool isPacked(PixelLayout layout) { return packedBytesPerPixel(layout) > 0; }

int packedBytesPerPixel(PixelLayout layout) {
  switch (layout) {
    case PixelLayout::kYuyv: return 2;
    case PixelLayout::kRgb888:
    case PixelLayout::kBgr888: return 3;
    case PixelLayout::kXrgb8888: return 4;
    default: return 0;
  }
}

std::array<int, 3> packedRgbByteOffsets(PixelLayout layout) {
  switch (layout) {
    case PixelLayout::kRgb888:
    case PixelLayout::kXrgb8888: return {2, 1, 0};
    case PixelLayout::kBgr888: return {0, 1, 2};
    default: return {-1, -1, -1};
  }
}

const char* layoutName(PixelLayout layout) {
  switch (layout) {
    case PixelLayout::kRgb8: return "RGB";
    case PixelLayout::kI420: return "YUV420";
    case PixelLayout::kNv12: return "NV12";
    case PixelLayout::kYuyv: return "YUYV";
    case PixelLayout::kRgb888: return "RGB888";
    case PixelLayout::kBgr888: return "BGR888";
    case PixelLayout::kXrgb8888: return "XRGB8888";
  }
  return "?";
}

LumaView FrameBuffer::luma() const {
  if (layout == PixelLayout::kI420 || layout == PixelLayout::kNv12)
    return LumaView{planes.data[0], width_px, height_px, planes.stride_bytes[0]};
  return LumaView{luma_storage.data(), width_px, height_px, width_px};
}

ImageRGB8 FrameBuffer::toRgb() const {
  if (layout == PixelLayout::kRgb8) return rgb;
  ImageRGB8 out;
  out.resize(width_px, height_px);
  for (int y = 0; y < height_px; ++y)
    for (int x = 0; x < width_px; ++x) {
      const glm::u8vec3 p = rgbAt(x, y);
      std::uint8_t* pixel = out.row(y) + 3 * x;
      pixel[0] = p.r;
      pixel[1] = p.g;
      pixel[2] = p.b;
    }
  return out;
}

glm::u8vec3 FrameBuffer::rgbAt(int x, int y) const {
  if (layout == PixelLayout::kRgb8) {
    const std::uint8_t* p = rgb.row(y) + 3 * x;
    return {p[0], p[1], p[2]};
  }
  const std::uint8_t* row = planes.data[0] + static_cast<std::size_t>(y) * static_cast<std::size_t>(planes.stride_bytes[0]);
  if (!isYuv(layout)) {
    const std::uint8_t* pixel = row + packedBytesPerPixel(layout) * x;
    const std::array<int, 3> at = packedRgbByteOffsets(layout);
    return {pixel[at[0]], pixel[at[1]], pixel[at[2]]};
  }
  float luma_code = 0.0f, cb = 128.0f, cr = 128.0f;
  if (layout == PixelLayout::kYuyv) {
    // Pair k holds Y'(2k) Cb(k) Y'(2k+1) Cr(k); chroma k sits on pixel 2k,
    // so an odd pixel lies halfway to pair k + 1 (the last one has none).
    luma_code = row[2 * x];
    const int pair = x / 2, pair_count = (width_px + 1) / 2;
    const std::uint8_t* here = row + 4 * pair;
    cb = here[1];
    cr = here[3];
    if (x % 2 == 1 && pair + 1 < pair_count) {
      cb = 0.5f * (cb + here[5]);
      cr = 0.5f * (cr + here[7]);
    }
  } else {
    luma_code = row[x];
    const std::size_t chroma_row = static_cast<std::size_t>(y / 2);
    if (layout == PixelLayout::kNv12) {
      const std::uint8_t* pair = planes.data[1] + chroma_row * planes.stride_bytes[1] + 2 * (x / 2);
      cb = pair[0];
      cr = pair[1];
    } else {
      cb = planes.data[1][chroma_row * planes.stride_bytes[1] + x / 2];
      cr = planes.data[2][chroma_row * planes.stride_bytes[2] + x / 2];
    }
  }
  const YcbcrDecoding decoding = ycbcrDecoding(planes.encoding);
  const float code[3] = {luma_code / 255.0f, cb / 255.0f, cr / 255.0f};
  glm::u8vec3 out;
  for (int row_index = 0; row_index < 3; ++row_index) {
    // Column-major: element (row, column) at matrix[column * 3 + row].
    float value = decoding.offset[row_index];
    for (int column = 0; column < 3; ++column) value += decoding.matrix[column * 3 + row_index] * code[column];
    out[row_index] = static_cast<std::uint8_t>(std::lround(255.0f * std::clamp(value, 0.0f, 1.0f)));
  }
  return out;
}

void FrameBuffer::finishRgb() {
  layout = PixelLayout::kRgb8;
  width_px = rgb.width;
  height_px = rgb.height;
  lumaFromRgb(rgb, luma_storage);
  planes = FramePlanes{};
}

FramePlanes& FrameBuffer::allocateYuv420(PixelLayout yuv_layout, int width, int height, const YcbcrEncoding& encoding) {
  layout = yuv_layout == PixelLayout::kNv12 ? PixelLayout::kNv12 : PixelLayout::kI420;
  width_px = width;
  height_px = height;
  const int chroma_width = (width + 1) / 2, chroma_height = (height + 1) / 2;
  const std::size_t luma_bytes = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  const std::size_t chroma_bytes = static_cast<std::size_t>(chroma_width) * static_cast<std::size_t>(chroma_height);
  plane_storage.resize(luma_bytes + 2 * chroma_bytes);
  planes = FramePlanes{};
  planes.encoding = encoding;
  planes.data[0] = plane_storage.data();
  planes.data[1] = plane_storage.data() + luma_bytes;
  planes.data[2] = plane_storage.data() + luma_bytes + chroma_bytes;
  planes.stride_bytes[0] = width;
  planes.stride_bytes[1] = planes.stride_bytes[2] = chroma_width;
  if (layout == PixelLayout::kNv12) {  // one plane of Cb Cr pairs, same bytes
    planes.stride_bytes[1] = 2 * chroma_width;
    planes.data[2] = nullptr;
    planes.stride_bytes[2] = 0;
  }
  rgb = ImageRGB8{};
  luma_storage.clear();
  return planes;
}

FramePlanes& FrameBuffer::allocatePacked(PixelLayout packed_layout, int width, int height, const YcbcrEncoding& encoding) {
  layout = isPacked(packed_layout) ? packed_layout : PixelLayout::kBgr888;
  width_px = width;
  height_px = height;
  // YUYV rows hold whole pairs: an odd width's last pair has one pixel.
  const int row_pixels = layout == PixelLayout::kYuyv ? 2 * ((width + 1) / 2) : width;
  const int stride = packedBytesPerPixel(layout) * row_pixels;
  plane_storage.resize(static_cast<std::size_t>(stride) * static_cast<std::size_t>(height));
  planes = FramePlanes{};
  planes.encoding = encoding;
  planes.data[0] = plane_storage.data();
  planes.stride_bytes[0] = stride;
  rgb = ImageRGB8{};
  luma_storage.clear();
  return planes;
}

void FrameBuffer::finishPacked() {
  luma_storage.resize(static_cast<std::size_t>(width_px) * static_cast<std::size_t>(height_px));
  const int step = packedBytesPerPixel(layout);
  const std::array<int, 3> at = packedRgbByteOffsets(layout);
  for (int y = 0; y < height_px; ++y) {
    const std::uint8_t* row = planes.data[0] + static_cast<std::size_t>(y) * static_cast<std::size_t>(planes.stride_bytes[0]);
    std::uint8_t* out = luma_storage.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(width_px);
    if (layout == PixelLayout::kYuyv) {
      for (int x = 0; x < width_px; ++x) out[x] = row[2 * x];
    } else {
      for (int x = 0, offset = 0; x < width_px; ++x, offset += step)
        out[x] = lumaCodeOfRgb(row[offset + at[0]], row[offset + at[1]], row[offset + at[2]]);
    }
  }
}

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
  if (thread_.joinable()) {
    if (!ended_) return true;
    stop();  // a stream that ended or failed starts over (a reconnect)
  }
  if (!prepare(error)) return false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    // Frames of the old stream are dropped: their pictures are stale.
    for (FrameBuffer* buffer : ready_) free_.push_back(buffer);
    ready_.clear();
    stopping_ = false;
    ended_ = false;
    failed_ = false;
    error_.clear();
  }
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

bool ThreadedFrameSource::pauseUnlessStopped(std::chrono::milliseconds duration) {
  std::unique_lock<std::mutex> lock(mutex_);
  return !changed_.wait_for(lock, duration, [&] { return stopping_; });
}

void ThreadedFrameSource::run() {
  // The numbering carries on across restarts: a reconnected camera's frames
  // follow the old ones (the simulated world's clock does not rewind).
  for (;; ++next_index_) {
    const std::uint64_t index = next_index_;
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
    handedOut(*lease);
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
