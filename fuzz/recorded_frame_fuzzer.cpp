// A recorded frame's metadata (run --record: DIR/frame_NNNNNN.json,
// readRecordedFrame), as replay and analyze read it: a frame whose every
// plane lies inside the bytes read, or nothing with one line naming the
// file. The .raw beside it holds 288 bytes (a 16x12 YUV420 frame), so
// that sizes, strides and plane counts are checked against a real file.
#include <vector>

#include "capture/frame_recording.hpp"
#include "fuzz/fuzz_input.hpp"

using namespace probelight;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool raw_written = [] {
    const std::vector<std::uint8_t> raw(288, 128);
    fuzz::writeInput(raw.data(), raw.size(), "frame_000000.raw");
    return true;
  }();
  (void)raw_written;
  const std::string path = fuzz::writeInput(data, size, "frame_000000.json");
  FrameBuffer frame;
  const Status status = readRecordedFrame(path, frame);
  if (!status.isOk()) {
    fuzz::requireOneLineNaming(status.message(), path);
    return 0;
  }
  fuzz::require(frame.width_px >= 1 && frame.height_px >= 1 && frame.width_px <= kMaxImageSidePx &&
                    frame.height_px <= kMaxImageSidePx,
                "a frame size out of 1..8192 accepted");
  fuzz::require(fuzz::finite(frame.metadata.exposure_us) && frame.metadata.exposure_us >= 0.0 &&
                    fuzz::finite(frame.metadata.analogue_gain) && frame.metadata.analogue_gain >= 0.0,
                "a non-finite or negative exposure accepted");
  if (frame.metadata.truth) {
    const FrameTruth& truth = *frame.metadata.truth;
    bool finite = fuzz::finite(truth.probe_radius_px) && fuzz::finite(truth.exposure) &&
                  fuzz::finite(truth.probe_center_px.x) && fuzz::finite(truth.probe_center_px.y);
    for (int c = 0; c < 3; ++c) {
      finite = finite && fuzz::finite(truth.pose.t_cam_from_world[c]);
      for (int r = 0; r < 3; ++r) finite = finite && fuzz::finite(truth.pose.R_cam_from_world[c][r]);
    }
    fuzz::require(finite && truth.probe_radius_px >= 0.0, "a non-finite or negative truth accepted");
  }
  // Every pixel and the luma read (AddressSanitizer checks they stay in the bytes read).
  const ImageRGB8 rgb = frame.toRgb();
  fuzz::require(rgb.width == frame.width_px && rgb.height == frame.height_px, "a decoded frame of another size");
  const LumaView luma = frame.luma();
  unsigned sum = 0;
  for (int y = 0; y < luma.height; ++y)
    for (int x = 0; x < luma.width; ++x) sum += luma.data[static_cast<std::size_t>(y) * luma.stride + x];
  (void)sum;
  return 0;
}
