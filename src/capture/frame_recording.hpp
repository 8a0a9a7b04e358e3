// A recording of what a camera gave: each frame's bytes exactly as they
// arrived (its planes at their own strides, Y'CbCr or packed RGB, before any
// conversion) and its metadata (exposure, gain, lens position, timestamp,
// format), so that a session on the board can be replayed frame for frame on
// a desktop (RecordingFrameSource), brackets included, and any one frame
// analysed (`probelight analyze --frame DIR/frame_000123.json`).
//
// A recording folder holds:
//   recording.json           what made it (RecordingHeader)
//   camera.yaml, rig.yaml    the calibration and rig it was seen through
//   frame_NNNNNN.raw         the planes, one after another, each its rows at its stride
//   frame_NNNNNN.json        that frame's metadata and layout (RecordedFrameHeader's fields)
// Frames are numbered from 0 in the order the kiosk received them; a frame's
// own camera sequence number is in its .json (gaps there are frames the
// camera dropped). Each frame is two small files rather than one big one so
// that a recording cut short (power, a full disk) keeps every frame written.
//
// A recording of the simulated camera also keeps what the simulator knows:
// each frame's truth (its "truth" object: pose, ball outline, exposure) and,
// in recording.json, the simulated world's settings ("simulation"), so that
// a replay measures the pipeline against the same truth as the live run
// without rendering a frame (the tests render a scene once and replay it).
//
// Every field is checked on reading: a bad file is one line naming the file
// and the field (Status::badInput).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "capture/frame_source.hpp"
#include "core/status.hpp"

namespace probelight {

inline constexpr int kRecordingVersion = 1;
inline constexpr const char* kRecordingHeaderFile = "recording.json";

// The simulated world a recording was rendered from: what sim::World needs
// besides the camera and rig (the recording's camera.yaml and rig.yaml), so
// that a replay rebuilds it for the truth.
struct RecordedSimulation {
  std::string environment;
  std::string camera_path;
  double noise_sigma_code = 0.0;
  double lens_blur_sigma_px = 0.0;
  std::uint64_t seed = 0;
  double sun_azimuth_rate_deg_per_frame = 0.0;
  double environment_rotation_deg = 0.0;
  std::int64_t lamp_on_frame = -1;
  std::int64_t lamp_off_frame = -1;
  double ball_offset_m[3] = {0.0, 0.0, 0.0};  // the real ball's offset from rig.yaml's (sim.ball_offset)
};

struct RecordingHeader {
  std::string source;            // FrameSource::name() of the camera recorded
  std::string stream;            // FrameSource::streamDescription(), may be empty
  bool exposure_control = false;  // the camera took exposure requests (a bracket can be replayed)
  std::optional<double> shortest_exposure_us;  // the sensor's, where it said
  std::optional<RecordedSimulation> simulation;  // a simulated camera's world
};

// A frame's bytes and metadata, copied out of the camera's buffer so that the
// buffer can go back to the camera at once and the writing happen later.
struct RecordedFrame {
  PixelLayout layout = PixelLayout::kRgb8;
  int width_px = 0;
  int height_px = 0;
  YcbcrEncoding encoding;
  int plane_count = 1;
  int stride_bytes[3] = {0, 0, 0};
  std::size_t plane_bytes[3] = {0, 0, 0};
  std::vector<std::uint8_t> bytes;  // the planes, one after another
  FrameMetadata metadata;           // truth too, where the simulator knew it (a camera has none)
};

// Rows of plane `plane` of a frame `height_px` high, and the bytes of pixels
// (not padding) in each of its rows.
int planeRows(PixelLayout layout, int plane, int height_px);
int planeRowBytes(PixelLayout layout, int plane, int width_px);

// "frame_000123" for frame 123 of a recording.
std::string recordedFrameStem(std::uint64_t index);

RecordedFrame copyFrameForRecording(const FrameBuffer& frame);

// Write DIR/recording.json, DIR/<stem>.raw and DIR/<stem>.json (the .json
// last, through a temporary name, so that a listed frame is a whole one).
// False, with `error` naming the file and why, when one cannot be written.
bool writeRecordingHeader(const std::string& dir, const RecordingHeader& header, std::string& error);
bool writeRecordedFrame(const std::string& dir, const std::string& stem, const RecordedFrame& frame,
                        std::string& error);

// DIR/recording.json, every field checked.
Status readRecordingHeader(const std::string& dir, RecordingHeader& header);
// The frames' .json files in DIR, in frame order.
std::vector<std::string> listRecordedFrames(const std::string& dir);
// Whether `path` names a recorded frame (its .json or its .raw), by name.
bool isRecordedFramePath(const std::string& path);
// A recorded frame into `frame`, as the camera gave it (the same layout and
// strides; luma computed as the live source computes it). `path` is the
// frame's .json or its .raw. Every field is checked against the .raw's size.
Status readRecordedFrame(const std::string& path, FrameBuffer& frame);

}  // namespace probelight
