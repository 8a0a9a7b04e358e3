// Frames from a recording (`probelight run --record DIR`, frame_recording.hpp),
// replayed as the camera gave them: the same pixel layout and strides, the
// same exposure, gain and timestamps, in the order they arrived. So a
// session on the board replays frame for frame on a desktop, and the
// pipeline's decisions (which depend on frames and their timestamps only)
// come out the same.
//
// Exposure: a recording of a camera with exposure control replays as one:
// lockExposure and setExposureLadder are taken (the recorded frames already
// hold what the camera did with the live run's requests), and each frame's
// metadata says its exposure, so a bracket the live run took is found again
// frame for frame by the same pipeline. A replay cannot take exposures that
// were never recorded: a bracket asked for at another frame than live (a
// button pressed at another moment) sees no rungs, and the bracket
// controller ends it as it would with a camera that ignored the request.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "capture/frame_recording.hpp"
#include "capture/frame_source.hpp"

namespace probelight {

class RecordingFrameSource : public ThreadedFrameSource {
 public:
  explicit RecordingFrameSource(std::string dir, int pool_size = 3);
  ~RecordingFrameSource() override;

  std::string name() const override { return "recording:" + dir_; }
  // The recorded stream's own description, with "replayed" (the report).
  std::string streamDescription() const override;
  // Whether the last start() failed on a bad recording.json (bad input).
  bool refusedItsSettings() const override { return header_bad_; }

  bool lockExposure(bool locked) override;
  bool setExposureLadder(const std::vector<ManualExposure>& per_frame) override;
  std::optional<double> shortestExposureUs() const override { return header_.shortest_exposure_us; }
  bool takesExposureLadders() const override { return header_.exposure_control; }

 protected:
  // Reads recording.json and lists the frames; fails with one line when the
  // header is bad or there are none.
  bool prepare(std::string& error) override;
  // The next frame file; one that cannot be read is skipped with a one-line
  // warning on stderr, and the replay goes on.
  Produced produce(std::uint64_t index, FrameBuffer& buffer, std::string& error) override;

 private:
  std::string dir_;
  RecordingHeader header_;
  bool header_bad_ = false;
  std::vector<std::string> frames_;
  std::size_t next_frame_ = 0;
  std::uint64_t frames_delivered_ = 0;
};

}  // namespace probelight
