// Frames from the board's camera through libcamera: the configured camera
// (the first by default), one stream (YUV420 at the configured size),
// requests queued and re-queued; libcamera's completion callback only hands
// the request over (it never blocks its thread), and the capture thread
// converts it into a pooled buffer and re-queues it. The Y plane is what
// tag detection reads; the RGB picture is uploaded (zero-copy dmabuf import
// is a later step).
//
// Differences between libcamera versions (Debian's 0.0.3, Raspberry Pi OS's
// 0.3-0.5) are confined to capture/libcamera_adapter.hpp.
#pragma once

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "capture/frame_source.hpp"

namespace libcamera {
class Camera;
class CameraManager;
class FrameBufferAllocator;
class Request;
class Stream;
}  // namespace libcamera

namespace probelight {

struct LibcameraSettings {
  std::string camera_id;  // empty: the first camera libcamera lists
  int width_px = 640;
  int height_px = 480;
  int buffer_count = 4;
};

class LibcameraSource final : public ThreadedFrameSource {
 public:
  explicit LibcameraSource(LibcameraSettings settings);
  ~LibcameraSource() override;
  std::string name() const override;

 protected:
  bool prepare(std::string& error) override;
  Produced produce(std::uint64_t index, FrameBuffer& buffer, std::string& error) override;

 private:
  struct Mapped;
  bool prepareCamera(std::string& error);
  void requestCompleted(libcamera::Request* request);
  void shutDown();

  LibcameraSettings settings_;
  std::unique_ptr<libcamera::CameraManager> manager_;
  std::shared_ptr<libcamera::Camera> camera_;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator_;
  libcamera::Stream* stream_ = nullptr;
  int stride_ = 0, width_ = 0, height_ = 0;
  std::vector<std::unique_ptr<libcamera::Request>> requests_;
  std::vector<std::unique_ptr<Mapped>> mapped_;
  bool started_ = false;

  std::mutex mutex_;
  std::condition_variable completed_changed_;
  std::deque<libcamera::Request*> completed_;
  bool disconnected_ = false;
  bool stopping_ = false;
};

// Why no camera was found, with the usual causes: one line.
std::string noCameraMessage(const std::string& wanted_id, const std::vector<std::string>& available);

}  // namespace probelight
