// `probelight run --record DIR`: every frame the camera gives, written to a
// recording (frame_recording.hpp) as it came, bracket frames included, off
// the render thread (core/write_queue.hpp). A frame's bytes are copied at
// once, so its buffer goes back to the camera at once; the writes wait for
// nothing but the queue. When the queue is full (the card slower than the
// camera) the kiosk waits: a recording with frames missing at random would
// not replay the bracket it holds. A write that fails (a full card) ends
// the recording there, said once; the kiosk goes on.
#pragma once

#include <cstdint>
#include <string>

#include "capture/frame_recording.hpp"
#include "core/write_queue.hpp"

namespace probelight {

class FrameRecorder {
 public:
  explicit FrameRecorder(std::string dir, int queue_depth = 4);

  // Writes DIR/recording.json. False, with `error` saying what could not be
  // written, when it cannot be.
  bool begin(const RecordingHeader& header, std::string& error);
  // Copies `frame` and queues it. False once, with `error`, when an earlier
  // write failed: the recording stops there (later calls do nothing).
  bool record(const FrameBuffer& frame, std::string& error);
  // Waits for the queued writes; false, with `error`, if any failed.
  bool finish(std::string& error);

  const std::string& dir() const { return dir_; }
  // The bytes of the frames queued so far.
  std::uint64_t bytesRecorded() const { return bytes_queued_; }
  // Frames whose files are written (all of them, after a successful finish()).
  int framesWritten() const { return queue_.written(); }
  bool stopped() const { return stopped_; }

 private:
  std::string dir_;
  WriteQueue<RecordedFrame> queue_;
  std::uint64_t frames_queued_ = 0;
  std::uint64_t bytes_queued_ = 0;
  bool stopped_ = false;
};

}  // namespace probelight
