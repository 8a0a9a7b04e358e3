// Frames from the board's camera through libcamera: the configured camera
// (the first by default), one YUV420 (or NV12) stream at the configured
// size, requests queued and re-queued.
//
// Zero-copy: each request's buffer is mapped once; a frame handed out is a
// lease on the request itself: its I420 planes are read in place (tag
// detection reads the Y' plane; the GPU imports the dmabuf or uploads the
// planes), and dropping the lease re-queues the request. libcamera's
// completion callback only hands the request over, so its thread never
// blocks. When several frames completed since the last wait, the newest is
// handed out and the older ones go straight back (lowest latency), except
// during an exposure bracket, whose frames are all handed out in order.
//
// Focus: camera.yaml's lens position, where it names one, goes in the start
// controls and the first request of each buffer (pipelines that ignore
// start controls still take it); the pipeline keeps it until another
// value is sent (the Pi's IPA does), so later requests carry none. Each
// frame's lens position comes in its metadata.
//
// Exposure: lockExposure(true) freezes auto exposure and white balance at
// their current values (the lights are being fitted from the ball's image);
// each frame's exposure time and gain come in its metadata.
//
// Differences between libcamera versions (Debian's 0.0.3, Raspberry Pi OS's
// 0.3-0.5) are confined to capture/libcamera_adapter.hpp.
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "capture/camera_format_choice.hpp"
#include "capture/exposure_sequencer.hpp"
#include "capture/frame_source.hpp"
#include "capture/lens_focus_choice.hpp"

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
  // probelight.yaml's camera.pixel_format: "auto" (the cheapest format the
  // camera offers; capture/camera_format_choice.hpp) or one by name.
  std::string pixel_format = "auto";
  // camera.yaml's lens_position_dioptres: the focus its intrinsics hold at,
  // set with autofocus off where the camera can drive its lens
  // (capture/lens_focus_choice.hpp). nullopt: the camera's own focus.
  std::optional<double> lens_position_dioptres;
};

class LibcameraSource final : public FrameSource {
 public:
  explicit LibcameraSource(LibcameraSettings settings);
  ~LibcameraSource() override;

  // Opens, configures and starts the camera; after a failure or a
  // disconnect, a later start() tries again from scratch (a reconnect).
  bool start(std::string& error) override;
  void stop() override;
  FrameWait waitFrame(std::chrono::milliseconds timeout, FrameLease& lease) override;
  std::string lastError() const override;
  std::string name() const override;
  bool lockExposure(bool locked) override;
  // ExposureTime and AnalogueGain with AE off, one re-queued request a
  // rung (a bracket); empty goes back to the lock state. While a ladder is
  // asked for, completed requests are handed over oldest first, all of them.
  bool setExposureLadder(const std::vector<ManualExposure>& per_frame) override;
  // The minimum of the camera's ExposureTime control, once started.
  std::optional<double> shortestExposureUs() const override;
  bool takesExposureLadders() const override;
  // The stream's colour encoding as the camera agreed it.
  YcbcrEncoding encoding() const { return encoding_; }
  // The stream the camera agreed to, once started: "BGR888 1920x1080
  // (stride 5760)", for the log and the run report.
  std::string streamDescription() const override;
  bool refusedItsSettings() const override { return settings_refused_; }
  std::string focusWarning() const override { return focus_.warning; }

 private:
  struct Slot;
  // Marks the start as failed on camera.pixel_format or camera.yaml's size.
  bool refuseSettings();
  bool startCamera(std::string& error);
  void requestCompleted(libcamera::Request* request);
  // Re-queues a request, with the exposure controls it needs.
  void requeue(libcamera::Request* request);
  void addExposureControls(libcamera::Request* request);
  Slot* slotOf(libcamera::Request* request);
  void shutDown();

  LibcameraSettings settings_;
  std::unique_ptr<libcamera::CameraManager> manager_;
  std::shared_ptr<libcamera::Camera> camera_;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator_;
  libcamera::Stream* stream_ = nullptr;
  int width_ = 0, height_ = 0;
  int strides_[3] = {0, 0, 0};
  YcbcrEncoding encoding_;
  CameraFormat format_ = CameraFormat::kYuv420;
  bool exposure_time_controllable_ = true;  // guarded by mutex_
  bool settings_refused_ = false;
  FocusRequest focus_;  // chosen at each start from the camera's controls
  std::string stream_description_;
  std::uint64_t undecodable_frames_ = 0;
  std::vector<std::unique_ptr<Slot>> slots_;
  bool started_ = false;
  // Buffers of each start() get fresh ids, so that an importer's cache
  // never mistakes a new stream's buffer for an old one.
  std::uint64_t generation_ = 0;
  std::uint64_t sequence_ = 0;

  mutable std::mutex mutex_;
  std::condition_variable completed_changed_;
  std::deque<libcamera::Request*> completed_;
  bool disconnected_ = false;
  bool stopping_ = false;
  std::string error_;
  // Exposure lock, bracket values, and what the pipeline already has.
  ExposureSequencer exposure_;
  std::optional<double> shortest_exposure_us_;
};

// Why no camera was found, with the usual causes: one line.
std::string noCameraMessage(const std::string& wanted_id, const std::vector<std::string>& available);

}  // namespace probelight
