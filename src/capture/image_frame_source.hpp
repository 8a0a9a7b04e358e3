// Frames from image files on disk: a folder or a glob(3) pattern, in name
// order. For replaying recorded sessions and for tests on real photos.
#pragma once

#include <string>
#include <vector>

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

  std::string name() const override { return "images:" + folder_or_pattern_; }
  // The files found by the last start() (valid after a successful start).
  const std::vector<std::string>& files() const { return files_; }

 protected:
  // Lists the files; fails with one line when none match.
  bool prepare(std::string& error) override;
  // Decodes the next file to RGB8 (metadata.origin = its path, sequence =
  // frame index). Undecodable files are skipped with a one-line warning on
  // stderr; the stream goes on.
  Produced produce(std::uint64_t index, FrameBuffer& buffer, std::string& error) override;

 private:
  std::string folder_or_pattern_;
  bool loop_;
  std::vector<std::string> files_;
  std::size_t next_file_ = 0;
  std::uint64_t frames_delivered_ = 0;  // a replay that decodes nothing is an error, not an empty run
};

}  // namespace probelight
