#include "capture/frame_recorder.hpp"

namespace probelight {

FrameRecorder::FrameRecorder(std::string dir, int queue_depth)
    : dir_(std::move(dir)),
      queue_([dir = dir_](const std::string& stem, const RecordedFrame& frame,
                          std::string& error) { return writeRecordedFrame(dir, stem, frame, error); },
             queue_depth) {}

bool FrameRecorder::begin(const RecordingHeader& header, std::string& error) {
  if (writeRecordingHeader(dir_, header, error)) return true;
  error = "cannot write " + error;
  return false;
}

bool FrameRecorder::record(const FrameBuffer& frame, std::string& error) {
  if (stopped_) return true;
  RecordedFrame copy = copyFrameForRecording(frame);
  const std::size_t bytes = copy.bytes.size();
  if (!queue_.push(recordedFrameStem(frames_queued_), std::move(copy), error)) {
    stopped_ = true;
    return false;
  }
  ++frames_queued_;
  bytes_queued_ += bytes;
  return true;
}

bool FrameRecorder::finish(std::string& error) { return queue_.finish(error); }

}  // namespace probelight
