// Frames from image files on disk: a folder or a glob(3) pattern, in name
// order. For replaying recorded sessions and for tests on real photos.
//
// Exposure sets (a replayed camera with exposure control): when the folder
// holds subfolders named ev<stops> (ev-2, ev-4, ev+1.5) with files named as
// its own, the folder's files count as taken at kReplayExposureUs (stops 0)
// and each set's at that times 2^stops. The source then has exposure
// control: a ladder (setExposureLadder) gets, frame by frame, the file of
// the set nearest the exposure asked for, and the frame's metadata says
// which exposure it got (as a sensor that clamps a request does).
// scripts/replay-frames.sh makes such sets with the simulator.
#pragma once

#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "capture/exposure_schedule.hpp"
#include "capture/frame_source.hpp"

namespace probelight {

class ImageFrameSource : public ThreadedFrameSource {
 public:
  // `folder_or_pattern`: a folder (its image files: .png .jpg .jpeg .bmp .tif
  // .tiff .pgm .ppm .pnm .webp, any case) or a glob pattern such as
  // "shots/*.jpg" (every regular file it matches). Files are sorted by name
  // (byte order). With `loop`, the list restarts after its last file.
  explicit ImageFrameSource(std::string folder_or_pattern, bool loop = false, int pool_size = 3);
  ~ImageFrameSource() override;

  // The exposure of a replay's own files when it has exposure sets: the
  // simulated camera's (SimFrameSource), which renders the sets.
  static constexpr double kReplayExposureUs = 10000.0;

  std::string name() const override { return "images:" + folder_or_pattern_; }
  // The files found by the last start() (valid after a successful start).
  const std::vector<std::string>& files() const { return files_; }
  // The exposure sets found by the last start(): (stops, folder), by stops.
  std::vector<std::pair<double, std::string>> exposureSets() const;

  // Exposure control, where the replay has exposure sets (false otherwise).
  bool lockExposure(bool locked) override;
  bool setExposureLadder(const std::vector<ManualExposure>& per_frame) override;
  bool takesExposureLadders() const override { return !exposureSets().empty(); }

 protected:
  // Lists the files; fails with one line when none match.
  bool prepare(std::string& error) override;
  // Decodes the next file to RGB8 (metadata.origin = its path, sequence =
  // frame index). Undecodable files are skipped with a one-line warning on
  // stderr; the stream goes on.
  Produced produce(std::uint64_t index, FrameBuffer& buffer, std::string& error) override;
  // The exposure schedule moves on with the frames handed out.
  void handedOut(const FrameBuffer& frame) override;

 private:
  std::string folder_or_pattern_;
  bool loop_;
  std::vector<std::string> files_;
  std::size_t next_file_ = 0;
  std::uint64_t frames_delivered_ = 0;  // a replay that decodes nothing is an error, not an empty run
  mutable std::mutex exposure_mutex_;    // the sets and the schedule: the consumer's thread and the producer's
  std::vector<std::pair<double, std::string>> exposure_sets_;
  ExposureSchedule exposure_schedule_;
};

}  // namespace probelight
