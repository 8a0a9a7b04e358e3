#include "capture/frame_source.hpp"

#include <algorithm>
#include <cmath>

namespace probelight {

int planeCount(PixelLayout layout) {
  return layout == PixelLayout::kI420 ? 3 : layout == PixelLayout::kNv12 ? 2 : 1;
}

bool isYuv(PixelLayout layout) { return layout == PixelLayout::kI420 || layout == PixelLayout::kNv12; }

LumaView FrameBuffer::luma() const {
  if (isYuv(layout)) return LumaView{yuv.data[0], width_px, height_px, yuv.stride_bytes[0]};
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
  if (!isYuv(layout)) {
    const std::uint8_t* p = rgb.row(y) + 3 * x;
    return {p[0], p[1], p[2]};
  }
  const std::uint8_t luma_code = yuv.data[0][static_cast<std::size_t>(y) * yuv.stride_bytes[0] + x];
  std::uint8_t cb = 128, cr = 128;
  const std::size_t chroma_row = static_cast<std::size_t>(y / 2);
  if (layout == PixelLayout::kNv12) {
    const std::uint8_t* pair = yuv.data[1] + chroma_row * yuv.stride_bytes[1] + 2 * (x / 2);
    cb = pair[0];
    cr = pair[1];
  } else {
    cb = yuv.data[1][chroma_row * yuv.stride_bytes[1] + x / 2];
    cr = yuv.data[2][chroma_row * yuv.stride_bytes[2] + x / 2];
  }
  const YcbcrDecoding decoding = ycbcrDecoding(yuv.encoding);
  const float code[3] = {luma_code / 255.0f, cb / 255.0f, cr / 255.0f};
  glm::u8vec3 out;
  for (int row = 0; row < 3; ++row) {
    // Column-major: element (row, column) at matrix[column * 3 + row].
    float value = decoding.offset[row];
    for (int column = 0; column < 3; ++column) value += decoding.matrix[column * 3 + row] * code[column];
    out[row] = static_cast<std::uint8_t>(std::lround(255.0f * std::clamp(value, 0.0f, 1.0f)));
  }
  return out;
}

void FrameBuffer::finishRgb() {
  layout = PixelLayout::kRgb8;
  width_px = rgb.width;
  height_px = rgb.height;
  lumaFromRgb(rgb, luma_storage);
  yuv = YuvPlanes{};
}

YuvPlanes& FrameBuffer::allocateYuv420(PixelLayout yuv_layout, int width, int height, const YcbcrEncoding& encoding) {
  layout = yuv_layout == PixelLayout::kNv12 ? PixelLayout::kNv12 : PixelLayout::kI420;
  width_px = width;
  height_px = height;
  const int chroma_width = (width + 1) / 2, chroma_height = (height + 1) / 2;
  const std::size_t luma_bytes = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  const std::size_t chroma_bytes = static_cast<std::size_t>(chroma_width) * static_cast<std::size_t>(chroma_height);
  yuv_storage.resize(luma_bytes + 2 * chroma_bytes);
  yuv = YuvPlanes{};
  yuv.encoding = encoding;
  yuv.data[0] = yuv_storage.data();
  yuv.data[1] = yuv_storage.data() + luma_bytes;
  yuv.data[2] = yuv_storage.data() + luma_bytes + chroma_bytes;
  yuv.stride_bytes[0] = width;
  yuv.stride_bytes[1] = yuv.stride_bytes[2] = chroma_width;
  if (layout == PixelLayout::kNv12) {  // one plane of Cb Cr pairs, same bytes
    yuv.stride_bytes[1] = 2 * chroma_width;
    yuv.data[2] = nullptr;
    yuv.stride_bytes[2] = 0;
  }
  rgb = ImageRGB8{};
  luma_storage.clear();
  return yuv;
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
