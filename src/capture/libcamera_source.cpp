#include "capture/libcamera_source.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <chrono>
#include <cstring>

#include <libcamera/camera_manager.h>
#include <libcamera/control_ids.h>
#include <libcamera/formats.h>
#include <libcamera/framebuffer_allocator.h>
#include <libcamera/request.h>
#include <opencv2/imgproc.hpp>

#include "capture/libcamera_adapter.hpp"

namespace probelight {

struct LibcameraSource::Mapped {
  std::vector<std::pair<void*, std::size_t>> regions;  // one per distinct dmabuf
  const std::uint8_t* planes[3] = {nullptr, nullptr, nullptr};
  ~Mapped() {
    for (auto& [address, length] : regions) ::munmap(address, length);
  }
};

std::string noCameraMessage(const std::string& wanted_id, const std::vector<std::string>& available) {
  if (available.empty())
    return "camera: libcamera found no camera: check the ribbon cable (seated, contacts the right way), "
           "camera_auto_detect=1 in /boot/firmware/config.txt, and that this user may open /dev/media* and "
           "/dev/dma_heap/* (group video); without a camera, use --source sim or --source images";
  std::string list;
  for (const std::string& id : available) list += (list.empty() ? "" : ", ") + id;
  return "camera: no camera '" + wanted_id + "' (libcamera lists " + list + ")";
}

LibcameraSource::LibcameraSource(LibcameraSettings settings) : ThreadedFrameSource(3), settings_(std::move(settings)) {}

LibcameraSource::~LibcameraSource() {
  stop();  // the capture thread first: it uses the camera
  shutDown();
}

std::string LibcameraSource::name() const {
  return "libcamera " + (camera_ ? camera_->id() : settings_.camera_id);
}

void LibcameraSource::shutDown() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  completed_changed_.notify_all();
  if (camera_) {
    if (started_) camera_->stop();
    camera_->requestCompleted.disconnect(this);
    camera_->release();
    camera_.reset();
  }
  requests_.clear();
  mapped_.clear();
  allocator_.reset();
  if (manager_) manager_->stop();
  manager_.reset();
}

bool LibcameraSource::prepare(std::string& error) {
  // libcamera allows one CameraManager per process: a failed start must not
  // keep its manager (a retry, or another source, makes a new one).
  if (!prepareCamera(error)) {
    shutDown();
    stopping_ = false;
    return false;
  }
  return true;
}

bool LibcameraSource::prepareCamera(std::string& error) {
  manager_ = std::make_unique<libcamera::CameraManager>();
  if (const int result = manager_->start(); result != 0) {
    error = std::string("camera: libcamera's camera manager did not start: ") + std::strerror(-result);
    return false;
  }
  std::vector<std::string> ids;
  for (const auto& camera : manager_->cameras()) ids.push_back(camera->id());
  camera_ = settings_.camera_id.empty() ? (ids.empty() ? nullptr : manager_->cameras().front())
                                        : manager_->get(settings_.camera_id);
  if (!camera_) {
    error = noCameraMessage(settings_.camera_id, ids);
    return false;
  }
  if (camera_->acquire() != 0) {
    error = "camera: " + camera_->id() + " is in use by another program (another probelight, rpicam-hello?)";
    camera_.reset();
    return false;
  }
  std::unique_ptr<libcamera::CameraConfiguration> config = libcamera_adapter::viewfinderConfiguration(*camera_);
  if (!config || config->size() != 1) {
    error = "camera: " + camera_->id() + " offers no viewfinder stream";
    return false;
  }
  libcamera::StreamConfiguration& stream_config = config->at(0);
  stream_config.pixelFormat = libcamera::formats::YUV420;
  stream_config.size = libcamera::Size(static_cast<unsigned>(settings_.width_px), static_cast<unsigned>(settings_.height_px));
  stream_config.bufferCount = static_cast<unsigned>(settings_.buffer_count);
  if (config->validate() == libcamera::CameraConfiguration::Invalid || stream_config.pixelFormat != libcamera::formats::YUV420 ||
      stream_config.size.width != static_cast<unsigned>(settings_.width_px) ||
      stream_config.size.height != static_cast<unsigned>(settings_.height_px)) {
    error = "camera: " + camera_->id() + " cannot stream YUV420 at " + std::to_string(settings_.width_px) + "x" +
            std::to_string(settings_.height_px) + " (it offers " + stream_config.toString() +
            "): match camera.yaml's size to one it offers";
    return false;
  }
  if (camera_->configure(config.get()) != 0) {
    error = "camera: " + camera_->id() + " refused the configuration " + stream_config.toString();
    return false;
  }
  stream_ = stream_config.stream();
  stride_ = static_cast<int>(stream_config.stride);
  width_ = static_cast<int>(stream_config.size.width);
  height_ = static_cast<int>(stream_config.size.height);
  allocator_ = std::make_unique<libcamera::FrameBufferAllocator>(camera_);
  if (allocator_->allocate(stream_) < 0) {
    error = "camera: cannot allocate buffers (is /dev/dma_heap/* readable by this user?)";
    return false;
  }
  for (const std::unique_ptr<libcamera::FrameBuffer>& frame : allocator_->buffers(stream_)) {
    std::unique_ptr<libcamera::Request> request = camera_->createRequest();
    if (!request || request->addBuffer(stream_, frame.get()) != 0) {
      error = "camera: cannot create a capture request";
      return false;
    }
    // Map each dmabuf once; planes are offsets into it.
    auto mapped = std::make_unique<Mapped>();
    int last_fd = -1;
    void* base = nullptr;
    for (std::size_t p = 0; p < frame->planes().size() && p < 3; ++p) {
      const auto& plane = frame->planes()[p];
      const int fd = libcamera_adapter::planeFd(plane);
      if (fd != last_fd) {
        const std::size_t length = ::lseek(fd, 0, SEEK_END);
        base = ::mmap(nullptr, length, PROT_READ, MAP_SHARED, fd, 0);
        if (base == MAP_FAILED) {
          error = std::string("camera: cannot map a frame buffer: ") + std::strerror(errno);
          return false;
        }
        mapped->regions.emplace_back(base, length);
        last_fd = fd;
      }
      mapped->planes[p] = static_cast<const std::uint8_t*>(base) + plane.offset;
    }
    mapped_.push_back(std::move(mapped));
    requests_.push_back(std::move(request));
  }
  camera_->requestCompleted.connect(this, &LibcameraSource::requestCompleted);
  camera_->disconnected.connect(this, [this] {
    std::lock_guard<std::mutex> lock(mutex_);
    disconnected_ = true;
    completed_changed_.notify_all();
  });
  if (camera_->start() != 0) {
    error = "camera: " + camera_->id() + " did not start streaming";
    return false;
  }
  started_ = true;
  for (std::unique_ptr<libcamera::Request>& request : requests_)
    if (camera_->queueRequest(request.get()) != 0) {
      error = "camera: cannot queue a capture request";
      return false;
    }
  return true;
}

// On libcamera's thread: only hand the request over.
void LibcameraSource::requestCompleted(libcamera::Request* request) {
  if (request->status() == libcamera::Request::RequestCancelled) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    completed_.push_back(request);
  }
  completed_changed_.notify_all();
}

ThreadedFrameSource::Produced LibcameraSource::produce(std::uint64_t index, FrameBuffer& buffer, std::string& error) {
  libcamera::Request* request = nullptr;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    completed_changed_.wait(lock, [&] { return stopping_ || disconnected_ || !completed_.empty(); });
    if (stopping_) return Produced::kEndOfStream;
    if (disconnected_) {
      error = "camera: " + camera_->id() + " disconnected";
      return Produced::kError;
    }
    request = completed_.front();
    completed_.pop_front();
  }
  std::size_t slot = 0;
  for (; slot < requests_.size() && requests_[slot].get() != request; ++slot) {
  }
  const Mapped& mapped = *mapped_[slot];
  // I420 to RGB; rows of stride bytes (chroma planes half of it).
  cv::Mat yuv(height_ * 3 / 2, width_, CV_8UC1);
  for (int y = 0; y < height_; ++y) std::memcpy(yuv.ptr(y), mapped.planes[0] + y * stride_, static_cast<std::size_t>(width_));
  const int chroma_stride = stride_ / 2, chroma_width = width_ / 2, chroma_height = height_ / 2;
  std::uint8_t* u = yuv.ptr(height_);
  std::uint8_t* v = u + chroma_width * chroma_height;
  for (int y = 0; y < chroma_height; ++y) {
    std::memcpy(u + y * chroma_width, mapped.planes[1] + y * chroma_stride, static_cast<std::size_t>(chroma_width));
    std::memcpy(v + y * chroma_width, mapped.planes[2] + y * chroma_stride, static_cast<std::size_t>(chroma_width));
  }
  buffer.rgb.resize(width_, height_);
  cv::Mat rgb(height_, width_, CV_8UC3, buffer.rgb.pixels.data());
  cv::cvtColor(yuv, rgb, cv::COLOR_YUV2RGB_I420);
  const libcamera::ControlList& metadata = request->metadata();
  buffer.metadata = FrameMetadata{};
  buffer.metadata.sequence = index;
  if (auto timestamp = metadata.get(libcamera::controls::SensorTimestamp)) buffer.metadata.timestamp_ns = *timestamp;
  if (auto exposure = metadata.get(libcamera::controls::ExposureTime)) buffer.metadata.exposure_us = *exposure;
  if (auto gain = metadata.get(libcamera::controls::AnalogueGain)) buffer.metadata.analogue_gain = *gain;
  buffer.metadata.origin = "camera:" + std::to_string(index);
  request->reuse(libcamera::Request::ReuseBuffers);
  if (camera_->queueRequest(request) != 0) {
    error = "camera: cannot re-queue a capture request";
    return Produced::kError;
  }
  return Produced::kFrame;
}

}  // namespace probelight
