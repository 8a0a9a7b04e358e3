#include "capture/libcamera_source.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>

#include <libcamera/camera_manager.h>
#include <libcamera/control_ids.h>
#include <libcamera/formats.h>
#include <libcamera/framebuffer_allocator.h>
#include <libcamera/request.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "capture/libcamera_adapter.hpp"
#include "capture/libcamera_log_levels.hpp"

namespace probelight {

// One request with its buffer mapped, and the FrameBuffer that describes it
// while it is lent out.
struct LibcameraSource::Slot {
  std::unique_ptr<libcamera::Request> request;
  libcamera::FrameBuffer* buffer = nullptr;
  std::vector<std::pair<void*, std::size_t>> regions;  // one mapping per distinct dmabuf
  const std::uint8_t* planes[3] = {nullptr, nullptr, nullptr};
  int fds[3] = {-1, -1, -1};
  std::uint32_t offsets[3] = {0, 0, 0};
  FrameBuffer frame;
  ~Slot() {
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

LibcameraSource::LibcameraSource(LibcameraSettings settings) : settings_(std::move(settings)) {}

LibcameraSource::~LibcameraSource() { shutDown(); }

std::string LibcameraSource::name() const {
  return "libcamera " + (camera_ ? camera_->id() : settings_.camera_id);
}

std::string LibcameraSource::streamDescription() const { return stream_description_; }

std::string LibcameraSource::lastError() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

void LibcameraSource::stop() { shutDown(); }

void LibcameraSource::shutDown() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  completed_changed_.notify_all();
  if (camera_) {
    // libcamera (0.0.3 to 0.4 at least) aborts here when the camera's
    // device is gone with requests still queued: VIDIOC_STREAMOFF fails,
    // the queued buffers are never returned, and PipelineHandler::stop()
    // asserts that no request is left. Not calling stop() does not help:
    // deleting the running camera then asserts in its IPA proxy, whose
    // thread only stop() ends. The service's unit restarts the process, on
    // the stored lighting (docs/board.md).
    if (started_) camera_->stop();  // cancels the queued requests
    camera_->requestCompleted.disconnect(this);
    camera_->disconnected.disconnect(this);
    camera_->release();
    camera_.reset();
  }
  started_ = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    completed_.clear();
  }
  slots_.clear();
  allocator_.reset();
  if (manager_) manager_->stop();
  manager_.reset();
}

bool LibcameraSource::start(std::string& error) {
  // A fresh start every time: after a disconnect the old camera object is
  // dead, and libcamera allows one CameraManager per process, so a failed
  // start must not keep its manager either.
  shutDown();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = false;
    disconnected_ = false;
    error_.clear();
  }
  ++generation_;
  settings_refused_ = false;
  if (!startCamera(error)) {
    shutDown();
    return false;
  }
  return true;
}

bool LibcameraSource::refuseSettings() {
  settings_refused_ = true;
  return false;
}

bool LibcameraSource::startCamera(std::string& error) {
  setLibcameraLogLevels("");
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
  {
    std::lock_guard<std::mutex> lock(mutex_);
    shortest_exposure_us_ = libcamera_adapter::exposureTimeMinUs(*camera_);
    exposure_time_controllable_ = libcamera_adapter::hasExposureTimeControl(*camera_);
  }
  focus_ = chooseFocusRequest(settings_.lens_position_dioptres, libcamera_adapter::lensControlsOffered(*camera_),
                              camera_->id());
  std::unique_ptr<libcamera::CameraConfiguration> config = libcamera_adapter::viewfinderConfiguration(*camera_);
  if (!config || config->size() != 1) {
    error = "camera: " + camera_->id() + " offers no viewfinder stream";
    return false;
  }
  libcamera::StreamConfiguration& stream_config = config->at(0);
  // The format: the cheapest the camera offers, or the one asked for.
  std::vector<std::string> offered;
  for (const libcamera::PixelFormat& format : stream_config.formats().pixelformats()) offered.push_back(format.toString());
  const std::optional<CameraFormat> format = chooseCameraFormat(offered, settings_.pixel_format, camera_->id(), error);
  if (!format) return refuseSettings();
  format_ = *format;
  const CameraFormatInfo& info = cameraFormatInfo(format_);
  const libcamera::PixelFormat wanted_format = libcamera::PixelFormat::fromString(info.libcamera_name);
  // The size: camera.yaml's, whose intrinsics hold for it alone.
  const FrameSizePx wanted_size{settings_.width_px, settings_.height_px};
  OfferedSizes sizes;
  for (const libcamera::Size& size : stream_config.formats().sizes(wanted_format))
    sizes.listed.push_back({static_cast<int>(size.width), static_cast<int>(size.height)});
  const libcamera::SizeRange range = stream_config.formats().range(wanted_format);
  if (range.max.width > 0 && range.max.height > 0) {
    sizes.range_min = FrameSizePx{static_cast<int>(range.min.width), static_cast<int>(range.min.height)};
    sizes.range_max = FrameSizePx{static_cast<int>(range.max.width), static_cast<int>(range.max.height)};
    sizes.width_step = static_cast<int>(std::max(range.hStep, 1u));
    sizes.height_step = static_cast<int>(std::max(range.vStep, 1u));
  }
  if (const std::optional<FrameSizePx> nearest = nearestOfferedSize(sizes, wanted_size)) {
    if (std::string problem = sizeMismatchProblem(camera_->id(), info.libcamera_name, wanted_size, *nearest);
        !problem.empty()) {
      error = problem;
      return refuseSettings();
    }
  }
  stream_config.pixelFormat = wanted_format;
  stream_config.size = libcamera::Size(static_cast<unsigned>(settings_.width_px), static_cast<unsigned>(settings_.height_px));
  stream_config.bufferCount = static_cast<unsigned>(settings_.buffer_count);
  // JPEG's full-range Rec601 for Y'CbCr: all 256 codes carry signal (the
  // ball's highlights and shadows), and it is what the ISP gives stills.
  // validate() may change it; the GPU decodes whatever it settles on.
  if (isYuv(info.layout)) stream_config.colorSpace = libcamera::ColorSpace::Sycc;
  if (config->validate() == libcamera::CameraConfiguration::Invalid || stream_config.pixelFormat != wanted_format) {
    error = "camera: " + camera_->id() + " cannot stream " + info.libcamera_name + " at " +
            std::to_string(settings_.width_px) + "x" + std::to_string(settings_.height_px) + " (it offers " +
            stream_config.toString() + ")";
    return refuseSettings();
  }
  if (std::string problem = sizeMismatchProblem(
          camera_->id(), info.libcamera_name, wanted_size,
          {static_cast<int>(stream_config.size.width), static_cast<int>(stream_config.size.height)});
      !problem.empty()) {
    error = problem;
    return refuseSettings();
  }
  if (camera_->configure(config.get()) != 0) {
    error = "camera: " + camera_->id() + " refused the configuration " + stream_config.toString();
    return false;
  }
  stream_ = stream_config.stream();
  width_ = static_cast<int>(stream_config.size.width);
  height_ = static_cast<int>(stream_config.size.height);
  // YUV420's chroma rows are half the luma stride; NV12's pairs fill a
  // row as long as the luma's; the packed formats and MJPEG have one plane.
  strides_[0] = static_cast<int>(stream_config.stride);
  strides_[1] = strides_[2] = info.layout == PixelLayout::kNv12 ? strides_[0] : strides_[0] / 2;
  const std::size_t plane_count = format_ == CameraFormat::kMjpeg ? 1 : static_cast<std::size_t>(planeCount(info.layout));
  const std::string format_name = info.libcamera_name;
  encoding_ = libcamera_adapter::encodingOf(stream_config.colorSpace);
  stream_description_ = format_name + " " + std::to_string(width_) + "x" + std::to_string(height_) + " (stride " +
                        std::to_string(strides_[0]) + (format_ == CameraFormat::kMjpeg ? ", decoded on the CPU" : "") +
                        ")";
  allocator_ = std::make_unique<libcamera::FrameBufferAllocator>(camera_);
  if (allocator_->allocate(stream_) < 0) {
    error = "camera: cannot allocate buffers (is /dev/dma_heap/* readable by this user?)";
    return false;
  }
  std::uint64_t slot_number = 0;
  for (const std::unique_ptr<libcamera::FrameBuffer>& buffer : allocator_->buffers(stream_)) {
    auto slot = std::make_unique<Slot>();
    slot->request = camera_->createRequest();
    slot->buffer = buffer.get();
    if (!slot->request || slot->request->addBuffer(stream_, buffer.get()) != 0) {
      error = "camera: cannot create a capture request";
      return false;
    }
    // Map each dmabuf once; planes are offsets into it.
    int last_fd = -1;
    void* base = nullptr;
    if (buffer->planes().size() != plane_count) {
      error = "camera: a " + format_name + " buffer came with " + std::to_string(buffer->planes().size()) +
              " planes, not " + std::to_string(plane_count);
      return false;
    }
    for (std::size_t p = 0; p < plane_count; ++p) {
      const auto& plane = buffer->planes()[p];
      const int fd = libcamera_adapter::planeFd(plane);
      if (fd != last_fd) {
        const off_t length = ::lseek(fd, 0, SEEK_END);
        base = length > 0 ? ::mmap(nullptr, static_cast<std::size_t>(length), PROT_READ, MAP_SHARED, fd, 0) : MAP_FAILED;
        if (base == MAP_FAILED) {
          error = std::string("camera: cannot map a frame buffer: ") + std::strerror(errno);
          return false;
        }
        slot->regions.emplace_back(base, static_cast<std::size_t>(length));
        last_fd = fd;
      }
      slot->planes[p] = static_cast<const std::uint8_t*>(base) + plane.offset;
      slot->fds[p] = fd;
      slot->offsets[p] = plane.offset;
    }
    FrameBuffer& frame = slot->frame;
    frame.layout = info.layout;
    frame.width_px = width_;
    frame.height_px = height_;
    for (std::size_t p = 0; p < plane_count; ++p) {
      frame.planes.data[p] = slot->planes[p];
      frame.planes.stride_bytes[p] = strides_[p];
      frame.planes.dmabuf_fd[p] = slot->fds[p];
      frame.planes.dmabuf_offset[p] = slot->offsets[p];
    }
    frame.planes.encoding = encoding_;
    frame.planes.buffer_id = (generation_ << 32) | ++slot_number;
    slots_.push_back(std::move(slot));
  }
  camera_->requestCompleted.connect(this, &LibcameraSource::requestCompleted);
  camera_->disconnected.connect(this, [this] {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      disconnected_ = true;
    }
    completed_changed_.notify_all();
  });
  libcamera::ControlList start_controls(camera_->controls());
  libcamera_adapter::setFocus(start_controls, focus_);
  if (camera_->start(&start_controls) != 0) {
    error = "camera: " + camera_->id() + " did not start streaming";
    return false;
  }
  started_ = true;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    exposure_.pipelineRestarted();
  }
  for (const std::unique_ptr<Slot>& slot : slots_) {
    addExposureControls(slot->request.get());
    libcamera_adapter::setFocus(slot->request->controls(), focus_);
    if (camera_->queueRequest(slot->request.get()) != 0) {
      error = "camera: cannot queue a capture request";
      return false;
    }
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

LibcameraSource::Slot* LibcameraSource::slotOf(libcamera::Request* request) {
  for (const std::unique_ptr<Slot>& slot : slots_)
    if (slot->request.get() == request) return slot.get();
  return nullptr;
}

bool LibcameraSource::lockExposure(bool locked) {
  std::lock_guard<std::mutex> lock(mutex_);
  exposure_.setLocked(locked);
  return true;
}

bool LibcameraSource::setExposureLadder(const std::vector<ManualExposure>& per_frame) {
  std::vector<ExposureSetting> ladder;
  for (const ManualExposure& exposure : per_frame) ladder.push_back({exposure.exposure_us, exposure.analogue_gain});
  std::lock_guard<std::mutex> lock(mutex_);
  // A camera without the control would hand back frames at its own
  // exposure while their ladder said otherwise: refuse, and the bracket
  // falls back to the single frame. Cancelling (an empty ladder) is fine.
  if (!ladder.empty() && !exposure_time_controllable_) return false;
  exposure_.setManual(ladder);
  return true;
}

bool LibcameraSource::takesExposureLadders() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return exposure_time_controllable_;
}

std::optional<double> LibcameraSource::shortestExposureUs() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return shortest_exposure_us_;
}

// The controls the exposure sequencer says this request must carry.
void LibcameraSource::addExposureControls(libcamera::Request* request) {
  ExposureControls controls;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    controls = exposure_.nextRequest();
  }
  switch (controls.kind) {
    case ExposureControls::Kind::kNone: break;
    case ExposureControls::Kind::kAuto:
      libcamera_adapter::setExposureLocked(request->controls(), camera_->controls(), false);
      break;
    case ExposureControls::Kind::kLocked:
      libcamera_adapter::setExposureLocked(request->controls(), camera_->controls(), true);
      break;
    case ExposureControls::Kind::kManual:
      libcamera_adapter::setManualExposure(request->controls(), camera_->controls(), controls.setting.exposure_us,
                                           controls.setting.analogue_gain);
      break;
  }
}

void LibcameraSource::requeue(libcamera::Request* request) {
  if (!camera_ || !started_) return;
  request->reuse(libcamera::Request::ReuseBuffers);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_ || disconnected_) return;
  }
  addExposureControls(request);
  if (camera_->queueRequest(request) != 0) {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = "camera: cannot re-queue a capture request";
    disconnected_ = true;
    completed_changed_.notify_all();
  }
}

FrameWait LibcameraSource::waitFrame(std::chrono::milliseconds timeout, FrameLease& lease) {
  std::vector<libcamera::Request*> stale;
  libcamera::Request* request = nullptr;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!completed_changed_.wait_for(lock, timeout,
                                     [&] { return stopping_ || disconnected_ || !completed_.empty(); }))
      return FrameWait::kTimeout;
    if (disconnected_) {
      if (error_.empty()) error_ = "camera: " + (camera_ ? camera_->id() : settings_.camera_id) + " disconnected";
      return FrameWait::kError;
    }
    if (stopping_) return FrameWait::kEndOfStream;
    if (exposure_.inBracket()) {
      // Each rung of a bracket is one frame: all of them, in order.
      request = completed_.front();
      completed_.pop_front();
    } else {
      // The newest frame; older ones would only add latency.
      request = completed_.back();
      completed_.pop_back();
      stale.assign(completed_.begin(), completed_.end());
      completed_.clear();
    }
  }
  for (libcamera::Request* old : stale) requeue(old);
  Slot* slot = slotOf(request);
  if (!slot) {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = "camera: a completed request that is not ours";
    return FrameWait::kError;
  }
  if (request->status() != libcamera::Request::RequestComplete) {
    // A frame the pipeline could not fill: drop it, keep streaming.
    requeue(request);
    return FrameWait::kTimeout;
  }
  FrameBuffer& frame = slot->frame;
  frame.metadata = FrameMetadata{};
  frame.metadata.sequence = sequence_++;
  const libcamera::ControlList& metadata = request->metadata();
  if (auto timestamp = metadata.get(libcamera::controls::SensorTimestamp)) frame.metadata.timestamp_ns = *timestamp;
  if (auto exposure = metadata.get(libcamera::controls::ExposureTime)) frame.metadata.exposure_us = *exposure;
  if (auto gain = metadata.get(libcamera::controls::AnalogueGain)) frame.metadata.analogue_gain = *gain;
  // Where the lens was (a camera with a lens reports it whether or not it
  // was asked to hold it); a value no lens reaches is left unknown, so that
  // a recording of it stays readable.
  if (auto lens = metadata.get(libcamera::controls::LensPosition);
      lens && *lens >= 0.0f && *lens <= kMaxLensPositionDioptres)
    frame.metadata.lens_position_dioptres = *lens;
  // The white balance's gains on red and blue: the object follows them as
  // it follows the exposure (stages/camera_response_follower.hpp).
  if (auto colour_gains = metadata.get(libcamera::controls::ColourGains)) {
    frame.metadata.red_gain = (*colour_gains)[0];
    frame.metadata.blue_gain = (*colour_gains)[1];
  }
  if (frame.metadata.exposure_us > 0.0) {
    std::lock_guard<std::mutex> lock(mutex_);
    exposure_.onFrame({frame.metadata.exposure_us, frame.metadata.analogue_gain > 0.0 ? frame.metadata.analogue_gain : 1.0});
  }
  frame.metadata.origin = "camera:" + std::to_string(frame.metadata.sequence);
  if (format_ == CameraFormat::kMjpeg) {
    // Decoded here, on the consumer's thread, into the slot's RGB image.
    const std::size_t bytes_used = slot->buffer->metadata().planes()[0].bytesused;
    const cv::Mat compressed(1, static_cast<int>(bytes_used), CV_8UC1, const_cast<std::uint8_t*>(slot->planes[0]));
    cv::Mat decoded;
    try {
      decoded = cv::imdecode(compressed, cv::IMREAD_COLOR);
    } catch (const cv::Exception&) {
      decoded.release();
    }
    if (decoded.empty() || decoded.cols != width_ || decoded.rows != height_) {
      // A damaged JPEG (a USB hiccup): drop it, keep streaming.
      ++undecodable_frames_;
      requeue(request);
      return FrameWait::kTimeout;
    }
    frame.rgb.resize(width_, height_);
    cv::Mat rgb(height_, width_, CV_8UC3, frame.rgb.pixels.data());
    cv::cvtColor(decoded, rgb, cv::COLOR_BGR2RGB);
    frame.finishRgb();
  } else if (isPacked(frame.layout)) {
    frame.finishPacked();  // the luma tag detection reads
  }
  lease = FrameLease(&frame, [this, request](FrameBuffer*) { requeue(request); });
  return FrameWait::kFrame;
}

}  // namespace probelight
