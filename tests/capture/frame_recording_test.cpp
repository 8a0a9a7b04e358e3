// Recordings (issue 17, run --record): a frame written and read back is the
// frame the camera gave, in every layout, with its row padding and its
// metadata, byte for byte; a damaged file is refused with one line naming
// the file and the field.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <tuple>
#include <filesystem>
#include <fstream>
#include <random>

#include <nlohmann/json.hpp>

#include "capture/frame_recorder.hpp"
#include "capture/frame_recording.hpp"
#include "capture/sim_frame_source.hpp"
#include "random_image.hpp"

namespace probelight {
namespace {

namespace fs = std::filesystem;

using testing::randomImage;

// `frame`'s planes moved into storage whose rows are `padding` bytes longer
// than the tight ones, padding filled with 0xAB (a camera's buffer: the
// padding is not the picture), and, like a camera's last row, the last row
// of each plane ending at its pixels.
void padRows(FrameBuffer& frame, int padding, std::vector<std::uint8_t>& storage) {
  const int planes = planeCount(frame.layout);
  std::size_t total = 0;
  int strides[3] = {0, 0, 0};
  for (int p = 0; p < planes; ++p) {
    strides[p] = frame.planes.stride_bytes[p] + padding;
    total += static_cast<std::size_t>(strides[p]) * planeRows(frame.layout, p, frame.height_px);
  }
  storage.assign(total, 0xAB);
  std::size_t at = 0;
  for (int p = 0; p < planes; ++p) {
    const int rows = planeRows(frame.layout, p, frame.height_px);
    const int row_bytes = planeRowBytes(frame.layout, p, frame.width_px);
    for (int y = 0; y < rows; ++y)
      std::copy_n(frame.planes.data[p] + static_cast<std::size_t>(y) * frame.planes.stride_bytes[p], row_bytes,
                  storage.data() + at + static_cast<std::size_t>(y) * strides[p]);
    frame.planes.data[p] = storage.data() + at;
    frame.planes.stride_bytes[p] = strides[p];
    at += static_cast<std::size_t>(strides[p]) * rows;
  }
  storage.resize(total - static_cast<std::size_t>(padding));  // the last row stops at its pixels
}

class FrameRecording : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("probelight_frame_recording_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // One YUV420 frame written as frame_000000, its .json path returned.
  std::string writeOne() {
    const ImageRGB8 image = randomImage(16, 12, 3);
    FrameBuffer frame;
    encodeSimFrame(image, PixelLayout::kI420, frame);
    frame.metadata.exposure_us = 2500.0;
    std::string error;
    EXPECT_TRUE(writeRecordedFrame(dir_.string(), recordedFrameStem(0), copyFrameForRecording(frame), error)) << error;
    return (dir_ / "frame_000000.json").string();
  }

  nlohmann::json readJson(const std::string& path) const { return nlohmann::json::parse(std::ifstream(path)); }
  void writeJson(const std::string& path, const nlohmann::json& json) const { std::ofstream(path) << json.dump(); }

  fs::path dir_;
};

TEST_F(FrameRecording, EveryLayoutComesBackAsTheCameraGaveItPaddingAndMetadataIncluded) {
  // Odd sizes: 4:2:0 chroma and YUYV pairs round up.
  const ImageRGB8 image = randomImage(37, 23, 1);
  int index = 0;
  for (const PixelLayout layout : {PixelLayout::kRgb8, PixelLayout::kI420, PixelLayout::kNv12, PixelLayout::kYuyv,
                                   PixelLayout::kRgb888, PixelLayout::kBgr888, PixelLayout::kXrgb8888}) {
    SCOPED_TRACE(layoutName(layout));
    FrameBuffer frame;
    encodeSimFrame(image, layout, frame);
    std::vector<std::uint8_t> padded;
    if (layout != PixelLayout::kRgb8) padRows(frame, 27, padded);  // RGB frames are tight by definition
    frame.metadata.sequence = 1000 + index;
    frame.metadata.timestamp_ns = 123456789012345;
    frame.metadata.exposure_us = 1250.5;
    frame.metadata.analogue_gain = 2.25;
    frame.metadata.red_gain = 1.875;
    frame.metadata.blue_gain = 1.4375;
    frame.metadata.origin = "camera";
    std::string error;
    const std::string stem = recordedFrameStem(index++);
    ASSERT_TRUE(writeRecordedFrame(dir_.string(), stem, copyFrameForRecording(frame), error)) << error;

    FrameBuffer read;
    const Status status = readRecordedFrame((dir_ / (stem + ".json")).string(), read);
    ASSERT_TRUE(status.isOk()) << status.message();
    ASSERT_EQ(read.layout, layout);
    ASSERT_EQ(read.width_px, 37);
    ASSERT_EQ(read.height_px, 23);
    EXPECT_EQ(read.metadata.sequence, frame.metadata.sequence);
    EXPECT_EQ(read.metadata.timestamp_ns, frame.metadata.timestamp_ns);
    EXPECT_EQ(read.metadata.exposure_us, 1250.5);
    EXPECT_EQ(read.metadata.analogue_gain, 2.25);
    EXPECT_EQ(read.metadata.red_gain, 1.875);
    EXPECT_EQ(read.metadata.blue_gain, 1.4375);
    if (layout == PixelLayout::kRgb8) {
      EXPECT_EQ(read.rgb.pixels, frame.rgb.pixels);
    } else {
      EXPECT_TRUE(read.planes.encoding == frame.planes.encoding);
      for (int p = 0; p < planeCount(layout); ++p) {
        ASSERT_EQ(read.planes.stride_bytes[p], frame.planes.stride_bytes[p]) << "plane " << p;
        const int row_bytes = planeRowBytes(layout, p, 37);
        for (int y = 0; y < planeRows(layout, p, 23); ++y)
          ASSERT_TRUE(std::equal(frame.planes.data[p] + y * frame.planes.stride_bytes[p],
                                 frame.planes.data[p] + y * frame.planes.stride_bytes[p] + row_bytes,
                                 read.planes.data[p] + y * read.planes.stride_bytes[p]))
              << "plane " << p << " row " << y;
      }
    }
    // What the pipeline reads of it: the pixels and the luma tags are found in.
    EXPECT_EQ(read.toRgb().pixels, frame.toRgb().pixels);
    const LumaView expected = frame.luma(), got = read.luma();
    for (int y = 0; y < 23; ++y)
      ASSERT_TRUE(std::equal(expected.data + y * expected.stride, expected.data + y * expected.stride + 37,
                             got.data + y * got.stride))
          << "luma row " << y;
  }
  // The frames in order; a half-written .json (.partial) and other files are not frames.
  std::ofstream(dir_ / "frame_000009.json.partial") << "{";
  std::ofstream(dir_ / "notes.json") << "{}";
  const std::vector<std::string> listed = listRecordedFrames(dir_.string());
  ASSERT_EQ(listed.size(), 7u);
  for (std::size_t i = 0; i < listed.size(); ++i)
    EXPECT_EQ(fs::path(listed[i]).filename().string(), recordedFrameStem(i) + ".json");
}

TEST_F(FrameRecording, TheRecorderWritesEveryFrameAndItsHeader) {
  FrameRecorder recorder(dir_.string(), 2);
  RecordingHeader header;
  header.source = "sim:studio";
  header.stream = "NV12 16x12 (simulated)";
  header.exposure_control = true;
  header.shortest_exposure_us = 30.0;
  std::string error;
  ASSERT_TRUE(recorder.begin(header, error)) << error;
  const ImageRGB8 image = randomImage(16, 12, 4);
  for (int i = 0; i < 10; ++i) {  // more than the queue holds: record() waits, drops none
    FrameBuffer frame;
    encodeSimFrame(image, PixelLayout::kNv12, frame);
    frame.metadata.sequence = static_cast<std::uint64_t>(i);
    ASSERT_TRUE(recorder.record(frame, error)) << error;
  }
  ASSERT_TRUE(recorder.finish(error)) << error;
  EXPECT_EQ(recorder.framesWritten(), 10);
  RecordingHeader read;
  const Status status = readRecordingHeader(dir_.string(), read);
  ASSERT_TRUE(status.isOk()) << status.message();
  EXPECT_EQ(read.source, "sim:studio");
  EXPECT_EQ(read.stream, header.stream);
  EXPECT_TRUE(read.exposure_control);
  ASSERT_TRUE(read.shortest_exposure_us.has_value());
  EXPECT_EQ(*read.shortest_exposure_us, 30.0);
  const std::vector<std::string> frames = listRecordedFrames(dir_.string());
  ASSERT_EQ(frames.size(), 10u);
  for (int i = 0; i < 10; ++i) {
    FrameBuffer frame;
    const Status frame_status = readRecordedFrame(frames[static_cast<std::size_t>(i)], frame);
    ASSERT_TRUE(frame_status.isOk()) << frame_status.message();
    EXPECT_EQ(frame.metadata.sequence, static_cast<std::uint64_t>(i));
  }
}

// Each damage names the file and the field (or the size) in one line.
TEST_F(FrameRecording, DamagedFramesAreOneLineNamingTheFileAndTheField) {
  const std::string path = writeOne();
  const nlohmann::json good = readJson(path);
  struct Case {
    const char* what;
    std::function<void(nlohmann::json&)> damage;
    const char* expected;  // in the message
  };
  const std::vector<Case> cases = {
      {"no exposure", [](nlohmann::json& j) { j.erase("exposure_us"); }, "field 'exposure_us': missing"},
      {"negative exposure", [](nlohmann::json& j) { j["exposure_us"] = -1.0; }, "field 'exposure_us': -1.0 is outside"},
      {"exposure text", [](nlohmann::json& j) { j["exposure_us"] = "fast"; }, "field 'exposure_us': not a number"},
      {"huge gain", [](nlohmann::json& j) { j["analogue_gain"] = 1e300; }, "field 'analogue_gain'"},
      {"negative colour gain", [](nlohmann::json& j) { j["red_gain"] = -0.5; }, "field 'red_gain': -0.5 is outside"},
      {"colour gain text", [](nlohmann::json& j) { j["blue_gain"] = "warm"; }, "field 'blue_gain': not a number"},
      {"unknown format", [](nlohmann::json& j) { j["format"] = "GREY"; }, "field 'format': \"GREY\" is not one of"},
      {"zero width", [](nlohmann::json& j) { j["width_px"] = 0; }, "field 'width_px': 0 is outside [1, 8192]"},
      {"fractional height", [](nlohmann::json& j) { j["height_px"] = 12.5; }, "field 'height_px': not a whole number"},
      {"two planes for YUV420", [](nlohmann::json& j) { j["planes"].erase(2); }, "field 'planes': not a list of 3"},
      {"stride below the row", [](nlohmann::json& j) { j["planes"][1]["stride_bytes"] = 7; },
       "field 'planes[1].stride_bytes': 7 is outside [8, "},
      {"bytes not stride x rows", [](nlohmann::json& j) { j["planes"][0]["bytes"] = 191; },
       "field 'planes[0].bytes': 191 is not stride_bytes x rows = 192"},
      {"a raw file elsewhere", [](nlohmann::json& j) { j["raw"] = "../../etc/passwd"; }, "field 'raw'"},
      {"unknown matrix", [](nlohmann::json& j) { j["ycbcr"]["matrix"] = "Rec999"; }, "field 'ycbcr.matrix'"},
      {"no range", [](nlohmann::json& j) { j["ycbcr"].erase("range"); }, "field 'ycbcr.range': missing"},
      {"huge sequence", [](nlohmann::json& j) { j["sequence"] = 18446744073709551615ull; }, "field 'sequence'"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    nlohmann::json damaged = good;
    c.damage(damaged);
    writeJson(path, damaged);
    FrameBuffer frame;
    const Status status = readRecordedFrame(path, frame);
    ASSERT_EQ(status.kind(), Status::Kind::kBadInput);
    EXPECT_EQ(status.message().rfind(path + ": ", 0), 0u) << status.message();
    EXPECT_NE(status.message().find(c.expected), std::string::npos) << status.message();
    EXPECT_EQ(status.message().find('\n'), std::string::npos) << status.message();
  }
  // A recording from before the white balance's gains: read, gains unknown (0).
  {
    nlohmann::json older = good;
    older.erase("red_gain");
    older.erase("blue_gain");
    writeJson(path, older);
    FrameBuffer frame;
    ASSERT_TRUE(readRecordedFrame(path, frame).isOk());
    EXPECT_EQ(frame.metadata.red_gain, 0.0);
    EXPECT_EQ(frame.metadata.blue_gain, 0.0);
  }
  // Not JSON at all; and a .raw cut short by a byte (power lost mid-write).
  std::ofstream(path) << "{\"format\": ";
  FrameBuffer frame;
  Status status = readRecordedFrame(path, frame);
  EXPECT_EQ(status.kind(), Status::Kind::kBadInput);
  EXPECT_NE(status.message().find("not valid JSON"), std::string::npos) << status.message();
  writeJson(path, good);
  const fs::path raw = dir_ / "frame_000000.raw";
  fs::resize_file(raw, fs::file_size(raw) - 1);
  status = readRecordedFrame((dir_ / "frame_000000.raw").string(), frame);  // by its .raw: the same frame
  EXPECT_EQ(status.kind(), Status::Kind::kBadInput);
  EXPECT_NE(status.message().find(raw.string() + ": 287 bytes, but "), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("says its planes hold 288"), std::string::npos) << status.message();
}

// Where the lens was focused (issue 48) is kept with each frame; a frame
// without it (a fixed-focus camera, or a recording made before it was kept)
// still loads, its lens position unknown.
TEST_F(FrameRecording, TheLensPositionIsKeptAndFramesWithoutItStillLoad) {
  const std::string path = writeOne();
  FrameBuffer frame;
  ASSERT_TRUE(readRecordedFrame(path, frame).isOk());
  EXPECT_FALSE(frame.metadata.lens_position_dioptres.has_value());
  EXPECT_FALSE(readJson(path).contains("lens_position_dioptres"));

  FrameBuffer focused;
  encodeSimFrame(randomImage(16, 12, 4), PixelLayout::kNv12, focused);
  // 3 + 53/1024: exact in a float (libcamera's LensPosition) and in JSON, so compared exactly.
  focused.metadata.lens_position_dioptres = 3.0517578125;
  std::string error;
  ASSERT_TRUE(writeRecordedFrame(dir_.string(), recordedFrameStem(1), copyFrameForRecording(focused), error)) << error;
  const std::string focused_path = (dir_ / "frame_000001.json").string();
  ASSERT_TRUE(readRecordedFrame(focused_path, frame).isOk());
  EXPECT_EQ(frame.metadata.lens_position_dioptres, 3.0517578125);

  const nlohmann::json good = readJson(focused_path);
  for (const auto& [value, expected] : std::vector<std::pair<nlohmann::json, std::string>>{
           {-0.5, "field 'lens_position_dioptres': -0.5 is outside [0.0, 100.0]"},
           {1000.0, "field 'lens_position_dioptres': 1000.0 is outside [0.0, 100.0]"},
           {"near", "field 'lens_position_dioptres': not a number"}}) {
    nlohmann::json damaged = good;
    damaged["lens_position_dioptres"] = value;
    writeJson(focused_path, damaged);
    const Status status = readRecordedFrame(focused_path, frame);
    ASSERT_EQ(status.kind(), Status::Kind::kBadInput) << value;
    EXPECT_EQ(status.message(), focused_path + ": " + expected);
  }
}

TEST_F(FrameRecording, ADamagedHeaderIsOneLineNamingTheField) {
  RecordingHeader header;
  FrameBuffer unused;
  Status status = readRecordingHeader(dir_.string(), header);
  EXPECT_EQ(status.kind(), Status::Kind::kBadInput);
  EXPECT_NE(status.message().find("recording.json: "), std::string::npos) << status.message();
  header.source = "libcamera";
  std::string error;
  ASSERT_TRUE(writeRecordingHeader(dir_.string(), header, error)) << error;
  const std::string path = (dir_ / kRecordingHeaderFile).string();
  const nlohmann::json good = readJson(path);
  for (const auto& [field, value, expected] :
       std::vector<std::tuple<std::string, nlohmann::json, std::string>>{
           {"version", 2, "field 'version': 2 is not 1"},
           {"format", "something else", "field 'format'"},
           {"exposure_control", "yes", "field 'exposure_control': not true or false"},
           {"shortest_exposure_us", -5.0, "field 'shortest_exposure_us'"},
           {"source", 3, "field 'source': not a string"}}) {
    nlohmann::json damaged = good;
    damaged[field] = value;
    writeJson(path, damaged);
    status = readRecordingHeader(dir_.string(), header);
    ASSERT_EQ(status.kind(), Status::Kind::kBadInput) << field;
    EXPECT_EQ(status.message().rfind(path + ": ", 0), 0u) << status.message();
    EXPECT_NE(status.message().find(expected), std::string::npos) << status.message();
  }
}

// A simulated camera's recording keeps the simulator's truth with each
// frame and its world's settings in the header, exactly (17 significant
// digits round-trip a double), so that a replay measures against the same
// truth as the live run; damaged, each is one line naming the field.
TEST_F(FrameRecording, TheSimulatorsTruthAndWorldComeBackExactly) {
  const ImageRGB8 image = randomImage(16, 12, 5);
  FrameBuffer frame;
  encodeSimFrame(image, PixelLayout::kRgb8, frame);
  FrameTruth truth;
  const double angle = 0.7;  // a rotation about (1, 2, 2)/3 by 0.7 rad, built from its axis
  const glm::dvec3 axis = glm::dvec3(1.0, 2.0, 2.0) / 3.0;
  const glm::dmat3 cross(0.0, axis.z, -axis.y, -axis.z, 0.0, axis.x, axis.y, -axis.x, 0.0);
  truth.pose.R_cam_from_world = glm::dmat3(1.0) + std::sin(angle) * cross + (1.0 - std::cos(angle)) * cross * cross;
  truth.pose.t_cam_from_world = {0.0123456789012345, -0.1, 0.61};
  truth.probe_center_px = {301.25, 199.0 / 3.0};
  truth.probe_radius_px = 29.875;
  truth.exposure = 0.3;
  truth.tag_fully_visible = true;
  truth.probe_fully_visible = false;
  frame.metadata.truth = truth;
  std::string error;
  ASSERT_TRUE(writeRecordedFrame(dir_.string(), recordedFrameStem(0), copyFrameForRecording(frame), error)) << error;
  const std::string path = (dir_ / "frame_000000.json").string();
  FrameBuffer read;
  Status status = readRecordedFrame(path, read);
  ASSERT_TRUE(status.isOk()) << status.message();
  ASSERT_TRUE(read.metadata.truth.has_value());
  const FrameTruth& got = *read.metadata.truth;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) EXPECT_EQ(got.pose.R_cam_from_world[c][r], truth.pose.R_cam_from_world[c][r]);
  EXPECT_EQ(got.pose.t_cam_from_world, truth.pose.t_cam_from_world);
  EXPECT_EQ(got.probe_center_px, truth.probe_center_px);
  EXPECT_EQ(got.probe_radius_px, truth.probe_radius_px);
  EXPECT_EQ(got.exposure, truth.exposure);
  EXPECT_TRUE(got.tag_fully_visible);
  EXPECT_FALSE(got.probe_fully_visible);

  // A camera's frame has none.
  frame.metadata.truth.reset();
  ASSERT_TRUE(writeRecordedFrame(dir_.string(), recordedFrameStem(1), copyFrameForRecording(frame), error)) << error;
  status = readRecordedFrame((dir_ / "frame_000001.json").string(), read);
  ASSERT_TRUE(status.isOk()) << status.message();
  EXPECT_FALSE(read.metadata.truth.has_value());

  const nlohmann::json good = readJson(path);
  for (const auto& [what, damage, expected] :
       std::vector<std::tuple<std::string, std::function<void(nlohmann::json&)>, std::string>>{
           {"not an object", [](nlohmann::json& j) { j["truth"] = 3; }, "field 'truth': not an object"},
           {"a scaled rotation", [](nlohmann::json& j) { j["truth"]["R_cam_from_world"][0] = 0.5; },
            "field 'truth.R_cam_from_world': not a rotation"},
           {"eight entries", [](nlohmann::json& j) { j["truth"]["R_cam_from_world"].erase(8); },
            "field 'truth.R_cam_from_world': not a list of 9 numbers"},
           {"a NaN-like entry", [](nlohmann::json& j) { j["truth"]["t_cam_from_world_m"][1] = nullptr; },
            "field 'truth.t_cam_from_world_m': holds null, not a number"},
           {"a negative radius", [](nlohmann::json& j) { j["truth"]["probe_radius_px"] = -1.0; },
            "field 'truth.probe_radius_px': -1.0 is outside"},
           {"no visibility", [](nlohmann::json& j) { j["truth"].erase("tag_fully_visible"); },
            "field 'truth.tag_fully_visible': missing"}}) {
    SCOPED_TRACE(what);
    nlohmann::json damaged = good;
    damage(damaged);
    writeJson(path, damaged);
    status = readRecordedFrame(path, read);
    ASSERT_EQ(status.kind(), Status::Kind::kBadInput);
    EXPECT_EQ(status.message().rfind(path + ": ", 0), 0u) << status.message();
    EXPECT_NE(status.message().find(expected), std::string::npos) << status.message();
    EXPECT_EQ(status.message().find('\n'), std::string::npos) << status.message();
  }

  RecordingHeader header;
  header.source = "sim:studio";
  RecordedSimulation simulation;
  simulation.environment = "sun_sky";
  simulation.camera_path = "static";
  simulation.noise_sigma_code = 1.5;
  simulation.lens_blur_sigma_px = 0.75;
  simulation.seed = 7;
  simulation.sun_azimuth_rate_deg_per_frame = 0.25;
  simulation.environment_rotation_deg = -30.0;
  simulation.lamp_on_frame = 40;
  simulation.lamp_off_frame = -1;
  simulation.ball_offset_m[0] = 0.004;
  simulation.ball_offset_m[2] = -0.002;
  header.simulation = simulation;
  ASSERT_TRUE(writeRecordingHeader(dir_.string(), header, error)) << error;
  RecordingHeader read_header;
  status = readRecordingHeader(dir_.string(), read_header);
  ASSERT_TRUE(status.isOk()) << status.message();
  ASSERT_TRUE(read_header.simulation.has_value());
  const RecordedSimulation& back = *read_header.simulation;
  EXPECT_EQ(back.environment, "sun_sky");
  EXPECT_EQ(back.camera_path, "static");
  EXPECT_EQ(back.noise_sigma_code, 1.5);
  EXPECT_EQ(back.lens_blur_sigma_px, 0.75);
  EXPECT_EQ(back.seed, 7u);
  EXPECT_EQ(back.sun_azimuth_rate_deg_per_frame, 0.25);
  EXPECT_EQ(back.environment_rotation_deg, -30.0);
  EXPECT_EQ(back.lamp_on_frame, 40);
  EXPECT_EQ(back.lamp_off_frame, -1);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(back.ball_offset_m[i], simulation.ball_offset_m[i]);
  const std::string header_path = (dir_ / kRecordingHeaderFile).string();
  nlohmann::json damaged = readJson(header_path);
  damaged["simulation"]["lamp_on_frame"] = -5;
  writeJson(header_path, damaged);
  status = readRecordingHeader(dir_.string(), read_header);
  ASSERT_EQ(status.kind(), Status::Kind::kBadInput);
  EXPECT_NE(status.message().find("field 'simulation.lamp_on_frame': -5 is outside"), std::string::npos)
      << status.message();
}

}  // namespace
}  // namespace probelight
