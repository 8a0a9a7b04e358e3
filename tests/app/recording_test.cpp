// `probelight run --record DIR` and `--source recording` (issue 17), through
// the real binary: a run recorded and replayed gives the same frames, pixel
// for pixel, and the same bracket and lights (the pipeline depends only on
// the frames, their metadata and their timestamps, all recorded); `analyze`
// takes a recorded frame and its bracket with the EVs from their metadata;
// a bad recording, flag or a full card is one line and loses nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include "binary_test_support.hpp"
#include "config/camera_file.hpp"
#include "config/rig_file.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"

namespace probelight {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;

class Recording : public testing::BinaryTest {
 protected:
  Recording() : BinaryTest("recording") {}

  // A sun_sky run whose start-up recalibration brackets the clipped sun, in
  // the simulated camera's `format`, recorded into DIR/<format>.rec.
  fs::path recordRun(const std::string& format, int frames, const std::string& extra_flags = "") {
    const fs::path config = dir_ / (format + ".yaml");
    std::ofstream(config) << "sim:\n  env: sun_sky\n  pixel_format: " << format << "\n";
    const fs::path recording = dir_ / (format + ".rec");
    const CommandResult result = run("run --frames " + std::to_string(frames) + " --path static --config " +
                                     config.string() + " --out " + (dir_ / (format + ".live")).string() +
                                     " --record " + recording.string() + " " + extra_flags);
    EXPECT_EQ(result.exit_status, 0) << result.stderr_text;
    return recording;
  }

  static nlohmann::json readJson(const fs::path& path) { return nlohmann::json::parse(std::ifstream(path)); }

  static std::vector<fs::path> framesOf(const fs::path& recording) {
    std::vector<fs::path> frames;
    for (const auto& entry : fs::directory_iterator(recording))
      if (entry.path().extension() == ".json" && entry.path().filename() != "recording.json")
        frames.push_back(entry.path());
    std::sort(frames.begin(), frames.end());
    return frames;
  }

  static std::string fileBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
};

TEST_F(Recording, ARecordedRunReplaysFrameForFrameItsBracketIncluded) {
  // A Pi camera's YUV420, a webcam's YUYV, and RGB as files give it.
  for (const std::string format : {"yuv420", "yuyv", "rgb"}) {
    SCOPED_TRACE(format);
    const fs::path recording = recordRun(format, 24, "--save-every 1");
    const fs::path live = dir_ / (format + ".live"), replay = dir_ / (format + ".replay");
    const nlohmann::json live_report = readReport(live);
    ASSERT_EQ(live_report["counters"]["brackets_merged"], 1) << "the run must bracket for this test to mean anything";

    // Every camera frame is in the recording, the bracket's rungs too: the
    // frames at a shorter exposure than the first one's.
    const std::vector<fs::path> frames = framesOf(recording);
    ASSERT_EQ(frames.size(), 24u);
    EXPECT_EQ(live_report["recording"]["frames_written"], 24);
    const double first_exposure_us = readJson(frames[0])["exposure_us"].get<double>();
    int shorter = 0;
    for (const fs::path& frame : frames) shorter += readJson(frame)["exposure_us"].get<double>() < first_exposure_us;
    EXPECT_GE(shorter, 2);

    // The replay: no --calibration or --rig (the recording's own).
    const CommandResult result =
        run("run --source recording --recording " + recording.string() + " --frames 0 --save-every 1 --config " +
            (dir_ / (format + ".yaml")).string() + " --out " + replay.string());
    ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
    const nlohmann::json replay_report = readReport(replay);
    EXPECT_EQ(replay_report["frames"], 24);
    EXPECT_EQ(replay_report["counters"]["brackets_merged"], 1);
    EXPECT_EQ(replay_report["hdr"]["frames"], live_report["hdr"]["frames"]);
    EXPECT_EQ(replay_report["hdr"]["clipped_lights"], live_report["hdr"]["clipped_lights"]);
    EXPECT_EQ(replay_report["lights"], live_report["lights"]);
    const std::string stream = replay_report["camera"]["stream"].get<std::string>();
    EXPECT_EQ(stream, live_report["camera"]["stream"].get<std::string>() + ", replayed");
    // The same pixels in, the same GL: the same pictures out, bit for bit.
    int compared = 0;
    for (const auto& entry : fs::directory_iterator(live)) {
      if (entry.path().extension() != ".png") continue;
      ++compared;
      ASSERT_TRUE(fs::exists(replay / entry.path().filename())) << entry.path().filename();
      EXPECT_TRUE(fileBytes(entry.path()) == fileBytes(replay / entry.path().filename())) << entry.path().filename();
    }
    EXPECT_GE(compared, 15);  // the frames shown (the bracket's are not)
  }
}

// A recorded frame and the bracket after it, given to analyze by their
// .json alone: each EV is the exposure ratio their metadata says, and the
// merged light is within the 5% mean of the full-HDR truth that
// AnalyzeBracket holds image files to. (It found that a pixel clipped in
// one channel was taken as measured in the others: NV12's clipped sun
// decodes to red 244, and the merge made it cyan, 7.4% off here; 0.8% now.)
TEST_F(Recording, AnalyzeTakesARecordedFrameAndItsBracketByTheirMetadata) {
  const fs::path recording = recordRun("nv12", 14, "--save-every 0");
  const std::vector<fs::path> frames = framesOf(recording);
  ASSERT_EQ(frames.size(), 14u);
  std::vector<double> exposures;
  for (const fs::path& frame : frames) exposures.push_back(readJson(frame)["exposure_us"].get<double>());
  std::size_t first_rung = 1;
  while (first_rung < frames.size() && exposures[first_rung] >= exposures[0]) ++first_rung;
  ASSERT_LT(first_rung + 2, frames.size()) << "no bracket recorded";
  const std::size_t base = first_rung - 1;
  std::string args = "analyze --frame " + frames[base].string() + " --out " + (dir_ / "analysis").string();
  std::map<std::string, double> expected_ev;
  for (std::size_t i = first_rung; i < first_rung + 3; ++i) {
    args += " --bracket " + frames[i].string();
    expected_ev[frames[i].string()] = std::log2(exposures[i] / exposures[base]);
  }
  // A recorded frame that does not say its exposure cannot be placed.
  nlohmann::json unsaid = readJson(frames[first_rung]);
  unsaid["exposure_us"] = 0.0;
  const fs::path unsaid_path = recording / "frame_000900.json";
  std::ofstream(unsaid_path) << unsaid.dump();
  args += " --bracket " + unsaid_path.string();

  const CommandResult result = run(args);
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  const nlohmann::json analysis = readJson(dir_ / "analysis" / "analysis.json");
  EXPECT_EQ(analysis["frame"]["exposure_us"].get<double>(), exposures[base]);
  ASSERT_EQ(analysis["hdr"]["method"], "bracket") << analysis["hdr"].dump(2);
  int used = 0;
  for (const auto& f : analysis["hdr"]["frames"]) {
    const std::string path = f["frame"].get<std::string>();
    if (path == unsaid_path.string()) {
      EXPECT_FALSE(f["used"].get<bool>());
      EXPECT_NE(f["reason"].get<std::string>().find("no exposure"), std::string::npos) << f.dump();
      continue;
    }
    ASSERT_TRUE(expected_ev.count(path)) << path;
    EXPECT_NEAR(f["ev"].get<double>(), expected_ev[path], 1e-9);
    if (f["used"].get<bool>()) {
      ++used;
      if (!f["measured_ev"].is_null()) {
        EXPECT_NEAR(f["measured_ev"].get<double>(), f["ev"].get<double>(), 0.5);
      }
    }
  }
  EXPECT_GE(used, 2) << analysis["hdr"].dump(1);
  EXPECT_EQ(testing::countOccurrences(result.stderr_text, "left out:"), 1u) << result.stderr_text;

  const sim::World world(sim::defaultScene());  // sun_sky, as recorded
  const std::uint64_t index = readJson(frames[base])["sequence"].get<std::uint64_t>();
  auto luminance = [](const glm::dvec3& rgb) { return 0.2126 * rgb.r + 0.7152 * rgb.g + 0.0722 * rgb.b; };
  double error = 0.0;
  ASSERT_EQ(analysis["irradiance"].size(), 14u);
  for (const auto& entry : analysis["irradiance"]) {
    const glm::dvec3 normal(entry["normal"][0].get<double>(), entry["normal"][1].get<double>(),
                            entry["normal"][2].get<double>());
    const glm::dvec3 rgb(entry["rgb"][0].get<double>(), entry["rgb"][1].get<double>(), entry["rgb"][2].get<double>());
    const double expected = luminance(world.irradiance(normal, index).hdr);
    error += std::abs(luminance(rgb) - expected) / expected / 14.0;
  }
  EXPECT_LE(error, 0.05);
}

// A recording of the simulated camera keeps the simulator's truth, so a
// replay is measured as the live run was (the tests render a scene once and
// replay it for each variant: probe_merge_run_test.cpp): the same pose and
// map errors, to the bit. And the replay depends on the recorded frames:
// one frame blacked out is one frame without the tag, and the maps made
// after it differ.
TEST_F(Recording, ASimulatedRunReplaysWithItsTruthAndFollowsItsFrames) {
  const fs::path config = dir_ / "still.yaml";
  std::ofstream(config) << "sim:\n  env: sun_sky\n  exposure_control: false\n";
  const int frames = 31;
  const fs::path recording = dir_ / "still.rec", live = dir_ / "live";
  CommandResult result = run("run --frames " + std::to_string(frames) + " --path static --save-every 0 --config " +
                             config.string() + " --out " + live.string() + " --record " + recording.string());
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  EXPECT_TRUE(readJson(recording / "recording.json").contains("simulation"));
  EXPECT_TRUE(readJson(recording / "frame_000000.json").contains("truth"));
  auto replay = [&](const fs::path& out) {
    const CommandResult replayed = run("run --source recording --recording " + recording.string() +
                                       " --frames 0 --save-every 0 --config " + config.string() + " --out " + out.string());
    EXPECT_EQ(replayed.exit_status, 0) << replayed.stderr_text;
    return readReport(out);
  };
  const nlohmann::json live_report = readReport(live);
  const nlohmann::json replay_report = replay(dir_ / "replay");
  ASSERT_TRUE(live_report["map_updates"].contains("truth_checks"));
  ASSERT_EQ(live_report["map_updates"]["truth_checks"].size(), 4u);  // frames 0, 10, 20, 30
  EXPECT_EQ(replay_report["map_updates"]["truth_checks"], live_report["map_updates"]["truth_checks"]);
  ASSERT_TRUE(live_report["accuracy"].contains("pose_rotation_error_deg"));
  EXPECT_EQ(replay_report["accuracy"], live_report["accuracy"]);
  EXPECT_EQ(replay_report["tag_status"]["frames"]["found"], frames);

  // Frame 15 blacked out: the replay loses the tag there, and follows the
  // frames it is given (the truth checks after it are of other maps).
  const fs::path raw = recording / "frame_000015.raw";
  std::ofstream(raw, std::ios::binary | std::ios::trunc)
      << std::string(static_cast<std::size_t>(fs::file_size(recording / "frame_000014.raw")), '\0');
  const nlohmann::json damaged = replay(dir_ / "damaged");
  EXPECT_EQ(damaged["tag_status"]["frames"]["found"], frames - 1);
  EXPECT_NE(damaged["accuracy"], live_report["accuracy"]);
}

// camera.yaml's lens position (issue 48) through the binary: a simulated
// camera with a lens (sim.lens_control, as the Camera Module 3) is held
// there, and every recorded frame and the recording's camera.yaml say so; a
// camera without one runs on after one warning line; a position no lens can
// have is one line and exit status 2.
TEST_F(Recording, CameraYamlsLensPositionIsHeldAndRecordedOrWarnedAbout) {
  CameraIntrinsics camera;
  camera.lens_position_dioptres = 2.5;
  const fs::path camera_file = dir_ / "camera.yaml", rig_file = dir_ / "rig.yaml";
  config::saveCameraFile(camera_file.string(), camera);
  config::saveRigFile(rig_file.string(), RigGeometry{});
  auto runWith = [&](const std::string& name, const std::string& sim_settings) {
    const fs::path config = dir_ / (name + ".yaml");
    std::ofstream(config) << "sim:\n" << sim_settings;
    return run("run --frames 3 --path static --save-every 0 --calibration " + camera_file.string() + " --rig " +
               rig_file.string() + " --config " + config.string() + " --out " + (dir_ / (name + ".out")).string() +
               " --record " + (dir_ / (name + ".rec")).string());
  };
  const CommandResult with_lens = runWith("lens", "  lens_control: true\n");
  ASSERT_EQ(with_lens.exit_status, 0) << with_lens.stderr_text;
  EXPECT_EQ(with_lens.stderr_text.find("lens_position_dioptres"), std::string::npos) << with_lens.stderr_text;
  const std::vector<fs::path> frames = framesOf(dir_ / "lens.rec");
  ASSERT_EQ(frames.size(), 3u);
  for (const fs::path& frame : frames) EXPECT_EQ(readJson(frame)["lens_position_dioptres"], 2.5) << frame;
  EXPECT_EQ(config::loadCameraFile((dir_ / "lens.rec" / "camera.yaml").string()).lens_position_dioptres, 2.5);

  const CommandResult fixed_focus = runWith("fixed", "  lens_control: false\n");
  ASSERT_EQ(fixed_focus.exit_status, 0) << fixed_focus.stderr_text;
  EXPECT_EQ(testing::countOccurrences(fixed_focus.stderr_text, "has no lens control"), 1u) << fixed_focus.stderr_text;
  EXPECT_NE(fixed_focus.stderr_text.find("warning: camera: sim:"), std::string::npos) << fixed_focus.stderr_text;
  for (const fs::path& frame : framesOf(dir_ / "fixed.rec"))
    EXPECT_FALSE(readJson(frame).contains("lens_position_dioptres")) << frame;

  // saveCameraFile refuses to write it: the value is put in by hand.
  std::string text = fileBytes(camera_file);
  const std::size_t field_at = text.find("lens_position_dioptres:");
  ASSERT_NE(field_at, std::string::npos) << text;
  text.replace(field_at, text.find('\n', field_at) - field_at, "lens_position_dioptres: -2");
  std::ofstream(camera_file, std::ios::trunc) << text;
  const CommandResult bad = runWith("bad", "  lens_control: true\n");
  EXPECT_EQ(bad.exit_status, 2) << bad.stderr_text;
  EXPECT_EQ(testing::countOccurrences(bad.stderr_text, "\n"), 1u) << bad.stderr_text;
  EXPECT_NE(bad.stderr_text.find(camera_file.string() + ": field 'lens_position_dioptres': -2 is out of range"),
            std::string::npos)
      << bad.stderr_text;
}

TEST_F(Recording, BadRecordingsAndFlagsAreOneLineAndLoseNothing) {
  const fs::path recording = recordRun("yuv420", 6, "--save-every 0");
  const std::size_t files = std::distance(fs::directory_iterator(recording), fs::directory_iterator());
  auto expectOneLine = [](const CommandResult& result, int status, const std::string& needle) {
    EXPECT_EQ(result.exit_status, status) << result.stderr_text;
    EXPECT_EQ(testing::countOccurrences(result.stderr_text, "\n"), 1u) << result.stderr_text;
    EXPECT_NE(result.stderr_text.find(needle), std::string::npos) << result.stderr_text;
  };
  const std::string out = " --out " + (dir_ / "out").string();
  // Recording over a recording would lose it: refused, nothing touched.
  expectOneLine(run("run --frames 3 --record " + recording.string() + out), 2, "already holds a recording");
  EXPECT_EQ(static_cast<std::size_t>(std::distance(fs::directory_iterator(recording), fs::directory_iterator())), files);
  expectOneLine(run("run --source recording" + out), 2, "--recording DIR");
  expectOneLine(run("run --recording " + recording.string() + out), 2, "only with --source recording");
  // An empty folder: its camera.yaml is the first thing missing.
  fs::create_directories(dir_ / "empty");
  expectOneLine(run("run --source recording --recording " + (dir_ / "empty").string() + out), 2,
                (dir_ / "empty" / "camera.yaml").string());
  // A recording.json from a later probelight.
  const fs::path header = recording / "recording.json";
  const std::string good_header = fileBytes(header);
  nlohmann::json later = nlohmann::json::parse(good_header);
  later["version"] = 9;
  std::ofstream(header) << later.dump();
  expectOneLine(run("run --source recording --recording " + recording.string() + out), 2,
                header.string() + ": field 'version': 9 is not 1");
  std::ofstream(header) << good_header;
  // A frame cut short (the card pulled mid-write): skipped with one line, the rest replayed.
  const fs::path raw = recording / "frame_000003.raw";
  fs::resize_file(raw, fs::file_size(raw) / 2);
  CommandResult result =
      run("run --source recording --recording " + recording.string() + " --frames 0 --save-every 0" + out);
  EXPECT_EQ(result.exit_status, 0) << result.stderr_text;
  EXPECT_EQ(testing::countOccurrences(result.stderr_text, "warning: skipping " + raw.string()), 1u)
      << result.stderr_text;
  EXPECT_EQ(readReport(dir_ / "out")["frames"], 5);

  // A full card (a file-size limit: writes fail with EFBIG): the recording
  // stops there, said once, and the kiosk runs on to its last frame.
  result = runWrapped("bash -c 'trap \"\" XFSZ; ulimit -f 700; exec \"$@\"' bash",
                      "run --frames 8 --save-every 0 --path static --record " + (dir_ / "full").string() +
                          " --out " + (dir_ / "full_out").string());
  EXPECT_EQ(result.exit_status, 0) << result.stderr_text;
  EXPECT_EQ(testing::countOccurrences(result.stderr_text, "recording stopped"), 1u) << result.stderr_text;
  const nlohmann::json report = readReport(dir_ / "full_out");
  EXPECT_EQ(report["frames"], 8);
  EXPECT_EQ(report["recording"]["frames_written"], 0);
  EXPECT_NE(report["recording"]["error"].get<std::string>().find("frame_000000.raw: File too large"), std::string::npos)
      << report["recording"].dump();
}

}  // namespace
}  // namespace probelight
