#include "capture/recording_frame_source.hpp"

#include <iostream>

namespace probelight {

RecordingFrameSource::RecordingFrameSource(std::string dir, int pool_size)
    : ThreadedFrameSource(pool_size), dir_(std::move(dir)) {}

RecordingFrameSource::~RecordingFrameSource() {
  // The base destructor would join the thread only after this object's
  // members (which produce() uses) are gone.
  stop();
}

std::string RecordingFrameSource::streamDescription() const {
  return header_.stream.empty() ? std::string() : header_.stream + ", replayed";
}

bool RecordingFrameSource::lockExposure(bool locked) {
  (void)locked;  // the recorded frames hold what the camera did
  return header_.exposure_control;
}

bool RecordingFrameSource::setExposureLadder(const std::vector<ManualExposure>& per_frame) {
  (void)per_frame;  // ditto: the rungs, if the live run took them here, are in the recording
  return header_.exposure_control;
}

bool RecordingFrameSource::prepare(std::string& error) {
  header_bad_ = false;
  if (const Status status = readRecordingHeader(dir_, header_); !status.isOk()) {
    header_bad_ = true;
    error = status.message();
    return false;
  }
  frames_ = listRecordedFrames(dir_);
  next_frame_ = 0;
  if (frames_.empty()) {
    header_bad_ = true;
    error = dir_ + ": the recording has no frames (frame_NNNNNN.json)";
    return false;
  }
  return true;
}

ThreadedFrameSource::Produced RecordingFrameSource::produce(std::uint64_t index, FrameBuffer& buffer,
                                                            std::string& error) {
  (void)index;  // frames keep their recorded sequence numbers
  while (next_frame_ < frames_.size()) {
    const std::string& path = frames_[next_frame_++];
    if (const Status status = readRecordedFrame(path, buffer); !status.isOk()) {
      std::cerr << "probelight: warning: skipping " << status.message() << "\n";
      continue;
    }
    ++frames_delivered_;
    return Produced::kFrame;
  }
  if (frames_delivered_ > 0) return Produced::kEndOfStream;
  error = dir_ + ": none of the recording's " + std::to_string(frames_.size()) + " frames could be read";
  return Produced::kError;
}

}  // namespace probelight
