// Stress cases of the environment-map path, through the real binary: a ball
// image blown out or covered, a ball cut by the frame edge, a ball smaller
// than the minimum, grazing tag views, and NaN/Inf in every float field of
// the three configuration files. Each must end with exit 0 and finite
// numbers (or, for a bad file, exit 2 and one line naming the field), say
// why on screen, and keep the last good maps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binary_test_support.hpp"
#include "config/camera_file.hpp"
#include "config/rig_file.hpp"
#include "ibl/camera_projection.hpp"
#include "sim/scene_config.hpp"
#include "sim/scene_geometry.hpp"
#include "sim/world.hpp"

namespace probelight {
namespace {

namespace fs = std::filesystem;

using testing::CommandResult;

class Stress : public testing::BinaryTest {
 protected:
  Stress() : BinaryTest("stress") {}


  void writeText(const fs::path& path, const std::string& text) const {
    std::ofstream out(path);
    out << text;
  }
};

// Every number in the report finite, and nothing null (a null is our
// writer's stand-in for a non-finite figure).
void expectAllFinite(const nlohmann::json& value, const std::string& path) {
  if (value.is_number()) {
    EXPECT_TRUE(std::isfinite(value.get<double>())) << path;
  } else if (value.is_null()) {
    ADD_FAILURE() << path << " is null (a non-finite figure)";
  } else if (value.is_object()) {
    for (const auto& [key, child] : value.items()) expectAllFinite(child, path + "." + key);
  } else if (value.is_array()) {
    for (size_t i = 0; i < value.size(); ++i) expectAllFinite(value[i], path + "[" + std::to_string(i) + "]");
  }
}

long long skipCount(const nlohmann::json& report, const std::string& reason) {
  const nlohmann::json& reasons = report["map_updates"]["skip_reasons"];
  return reasons.contains(reason) ? reasons[reason].get<long long>() : 0;
}

int lineCount(const std::string& text) {
  int lines = 0;
  for (char c : text) lines += c == '\n';
  return lines;
}

// --- Unusable ball images ---------------------------------------------------

// Frames of the simulator's static camera, replayed from PNGs; in frames
// 10-14 the ball's disc is painted white (a blown-out ball), in 15-19 black
// (a cap, a hand). The kiosk must skip those with their own reasons and keep
// the maps: the object, drawn from the maps, looks the same in frame 9 (before),
// 14 and 19 (during) and 25 (after). A map made from a white ball would
// light the object as if from a uniform sky at the clip level (the camera's
// white / probe_reflectance), far brighter than the studio, and a black one
// would leave only its ambient term: tens of codes either way.
TEST_F(Stress, SaturatedAndBlackBallImagesAreSkippedAndTheMapsKept) {
  sim::SceneConfig scene = sim::defaultScene();
  scene.environment = "studio";
  scene.camera_path.name = "static";
  const sim::World world(scene);
  const fs::path frames_dir = dir_ / "frames";
  fs::create_directories(frames_dir);
  const int frames = 26;
  std::vector<cv::Mat> inputs;
  for (int i = 0; i < frames; ++i) {
    ImageRGB8 image;
    FrameTruth truth;
    world.render(static_cast<std::uint64_t>(i), image, truth);
    ASSERT_TRUE(truth.probe_fully_visible);
    cv::Mat rgb(image.height, image.width, CV_8UC3, image.pixels.data());
    cv::Mat bgr;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    if (i >= 10 && i < 20) {
      // The whole disc plus 1.5 px: the kiosk's outline (from its own pose)
      // is within ~0.4 px of the truth, and the signature uses 0.9 r.
      const int value = i < 15 ? 255 : 0;
      cv::circle(bgr, cv::Point2d(truth.probe_center_px.x, truth.probe_center_px.y) * 16.0,
                 static_cast<int>((truth.probe_radius_px + 1.5) * 16.0), cv::Scalar(value, value, value), cv::FILLED,
                 cv::LINE_8, 4);
    }
    char name[32];
    std::snprintf(name, sizeof name, "f%03d.png", i);
    ASSERT_TRUE(cv::imwrite((frames_dir / name).string(), bgr));
    inputs.push_back(bgr);
  }
  config::saveCameraFile((dir_ / "camera.yaml").string(), scene.camera);
  config::saveRigFile((dir_ / "rig.yaml").string(), scene.rig);
  const fs::path out = dir_ / "out";
  const CommandResult result = run("run --source images --images " + frames_dir.string() + " --calibration " +
                                   (dir_ / "camera.yaml").string() + " --rig " + (dir_ / "rig.yaml").string() +
                                   " --display headless --frames 0 --out " + out.string());
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("Mirror ball image all white"), std::string::npos) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("Mirror ball image all black"), std::string::npos) << result.stderr_text;

  const nlohmann::json report = readReport(out);
  expectAllFinite(report["stages"], "stages");
  expectAllFinite(report["map_updates"], "map_updates");
  EXPECT_EQ(skipCount(report, "ball saturated"), 5) << report["map_updates"].dump();
  EXPECT_EQ(skipCount(report, "ball dark"), 5) << report["map_updates"].dump();
  EXPECT_EQ(report["stages"]["probe_to_cube"]["skip_reasons"]["ball saturated"], 5);
  EXPECT_EQ(report["stages"]["probe_to_cube"]["skip_reasons"]["ball dark"], 5);
  EXPECT_GE(report["counters"]["frames_with_status"].get<int>(), 10);
  // The unpainted frames are ordinary: none of them is called unusable.
  EXPECT_EQ(report["map_updates"]["updated"].get<int>() + report["map_updates"]["skipped"].get<int>(), frames);

  // The object, from the composites: where they differ from the input frame
  // (the background is a texel-exact copy), above the status bar.
  auto composite = [&](int i) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06d.png", i);
    return cv::imread((out / name).string(), cv::IMREAD_COLOR);
  };
  const cv::Mat before = composite(9);
  ASSERT_FALSE(before.empty());
  cv::Mat difference;
  cv::absdiff(before, inputs[9], difference);
  cv::Mat difference_max;
  cv::transform(difference, difference_max, cv::Matx13f(1, 1, 1));
  cv::Mat mask = difference_max > 6;
  // Erode: the rim moves with the pose's noise; the interior is what the maps set.
  cv::erode(mask, mask, cv::Mat::ones(5, 5, CV_8U));
  mask(cv::Rect(0, mask.rows - 40, mask.cols, 40)).setTo(0);
  ASSERT_GT(cv::countNonZero(mask), 200) << "no object drawn in frame 9";
  const cv::Scalar mean_before = cv::mean(before, mask);
  for (int i : {12, 14, 17, 19, 25}) {
    const cv::Mat after = composite(i);
    ASSERT_FALSE(after.empty()) << i;
    const cv::Scalar mean_after = cv::mean(after, mask);
    for (int c = 0; c < 3; ++c) {
      // The same maps, the same pose up to its noise (0.02 px on a static
      // camera): the object's mean moves by well under a code. 1.5 codes
      // leaves room for rounding and is far below what a white or black map
      // would do.
      EXPECT_NEAR(mean_after[c], mean_before[c], 1.5) << "frame " << i << " channel " << c;
    }
  }
}

// --- The ball out of view, too small; grazing views ----------------------

// The principal point moved so that the ball's centre lands on the image's
// edge while the whole tag stays in view: the simulator renders with that
// camera (it is given the file), the tag is tracked, and every frame is
// skipped as "ball not fully in view", with its status; no maps are ever made.
TEST_F(Stress, BallCutByTheFrameEdgeIsSkipped) {
  sim::SceneConfig scene = sim::defaultScene();
  scene.environment = "studio";
  scene.camera_path.name = "static";
  const sim::World world(scene);
  const PoseCamFromWorld pose = world.pose(0);
  const glm::dvec2 ball_px = ibl::projectToPixel(scene.camera, pose.toCamera(scene.rig.probe_center_w));
  const glm::dvec2 tag_px = ibl::projectToPixel(scene.camera, pose.toCamera(glm::dvec3(0.0)));
  CameraIntrinsics camera = scene.camera;
  camera.cx_px += ball_px.x > tag_px.x ? (camera.width_px - 1.0) - ball_px.x : -ball_px.x;
  // Precondition: the tag's corners stay inside with a margin.
  for (const glm::dvec3& corner : sim::tagCornersWorld(scene.rig.tag_size_m)) {
    const glm::dvec2 p = ibl::projectToPixel(camera, pose.toCamera(corner));
    ASSERT_GT(p.x, 10.0);
    ASSERT_LT(p.x, camera.width_px - 11.0);
  }
  config::saveCameraFile((dir_ / "camera.yaml").string(), camera);
  const fs::path out = dir_ / "out";
  const int frames = 6;
  const CommandResult result = run("run --source sim --path static --calibration " + (dir_ / "camera.yaml").string() +
                                   " --display headless --frames " + std::to_string(frames) + " --out " + out.string());
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("Mirror ball not fully in view"), std::string::npos) << result.stderr_text;
  const nlohmann::json report = readReport(out);
  expectAllFinite(report["stages"], "stages");
  expectAllFinite(report["accuracy"], "accuracy");
  EXPECT_FALSE(report["counters"].contains("frames_without_tag")) << "the tag must stay tracked";
  EXPECT_EQ(skipCount(report, "ball not fully in view"), frames);
  EXPECT_EQ(report["map_updates"]["updated"], 0);
  EXPECT_EQ(report["counters"]["frames_with_status"], frames);
}

// min_probe_radius_px raised above the ball's ~30 px: every frame "ball too
// small", with its status, no maps, exit 0.
TEST_F(Stress, BallSmallerThanTheMinimumIsSkipped) {
  writeText(dir_ / "probelight.yaml", "map_updates:\n  min_probe_radius_px: 1000\n");
  const fs::path out = dir_ / "out";
  const int frames = 5;
  const CommandResult result = run("run --source sim --path static --config " + (dir_ / "probelight.yaml").string() +
                                   " --display headless --frames " + std::to_string(frames) + " --out " + out.string());
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("Mirror ball too small"), std::string::npos) << result.stderr_text;
  const nlohmann::json report = readReport(out);
  expectAllFinite(report["stages"], "stages");
  expectAllFinite(report["accuracy"], "accuracy");
  EXPECT_EQ(skipCount(report, "ball too small"), frames);
  EXPECT_EQ(report["map_updates"]["updated"], 0);
  EXPECT_EQ(report["counters"]["frames_with_status"], frames);
}

// The random path: an independent pose each frame, including the grazing
// ones (the test finds the lowest elevation of the tag seen from the camera
// and requires one at or under 26 degrees). Every frame is accounted for and
// every number in the report is finite.
TEST_F(Stress, RandomPosesIncludingGrazingViewsGiveFiniteReports) {
  const int frames = 30;
  sim::SceneConfig scene = sim::defaultScene();
  scene.camera_path.name = "random";
  const sim::World world(scene);
  double lowest_elevation_deg = 90.0;
  for (int i = 0; i < frames; ++i) {
    const glm::dvec3 eye = world.pose(static_cast<std::uint64_t>(i)).cameraCenterWorld();
    lowest_elevation_deg = std::min(lowest_elevation_deg, std::asin(eye.z / glm::length(eye)) * 180.0 / M_PI);
  }
  std::printf("[ stress ] lowest tag elevation over %d random frames: %.1f deg\n", frames, lowest_elevation_deg);
  EXPECT_LE(lowest_elevation_deg, 26.0) << "the run would not test grazing views";

  const fs::path out = dir_ / "out";
  const CommandResult result = run("run --source sim --path random --display headless --frames " +
                                   std::to_string(frames) + " --out " + out.string());
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  const nlohmann::json report = readReport(out);
  EXPECT_EQ(report["frames"], frames);
  expectAllFinite(report["stages"], "stages");
  expectAllFinite(report["accuracy"], "accuracy");
  expectAllFinite(report["accuracy_detail"], "accuracy_detail");
  expectAllFinite(report["map_updates"], "map_updates");
  expectAllFinite(report["counters"], "counters");
  EXPECT_EQ(report["map_updates"]["updated"].get<int>() + report["map_updates"]["skipped"].get<int>(), frames);
}

// --- NaN / Inf in every float field ----------------------------------------

struct BadField {
  std::string file;       // "probelight", "camera", "rig"
  std::string yaml;       // the whole file, with VALUE where the bad number goes
  std::string field;      // what the error line must name
};

std::vector<BadField> badFields() {
  std::vector<BadField> out;
  // probelight.yaml: every float field (board/probelight.yaml lists them).
  const std::vector<std::pair<std::string, std::string>> app_scalars = {
      {"environment_maps", "camera_gamma"},      {"tracking", "quad_decimate"},
      {"tracking", "quad_sigma"},                {"object", "radius"},
      {"object", "k_specular"},                  {"object", "shininess"},
      {"object", "k_reflect"},                   {"map_updates", "min_probe_radius_px"},
      {"map_updates", "max_center_shift_px"},    {"map_updates", "max_radius_change_px"},
      {"map_updates", "max_rotation_change_deg"}, {"map_updates", "change_threshold_code"},
      {"map_updates", "smoothing_new_weight"},   {"sim", "noise_sigma"},
      {"sim", "sun_azimuth_rate_deg_per_frame"}, {"probe_refinement", "weight"},
      {"lights", "fade_s"},                      {"lights", "max_shadow_reach"},
      {"lights", "refit_change_fraction"},      {"button", "debounce_ms"},
      {"button", "long_press_ms"},              {"display", "refresh_hz"}};
  for (const auto& [section, name] : app_scalars)
    out.push_back({"probelight", section + ":\n  " + name + ": VALUE\n", section + "." + name});
  for (const std::string name : {"static_cutoff_hz", "max_lag_px", "speed_cutoff_hz", "reset_jump_px"})
    out.push_back({"probelight", "tracking:\n  smoothing:\n    " + name + ": VALUE\n", "tracking.smoothing." + name});
  for (int i = 0; i < 3; ++i) {
    std::string items = "[";
    for (int k = 0; k < 3; ++k) items += (k ? ", " : "") + (k == i ? std::string("VALUE") : std::string("0.0"));
    out.push_back({"probelight", "sim:\n  ball_offset: " + items + "]\n", "sim.ball_offset"});
  }
  for (const std::string vector : {"position", "albedo"})
    for (int i = 0; i < 3; ++i) {
      const std::string ok = vector == "position" ? "0.0" : "0.5";
      std::string items = "[";
      for (int k = 0; k < 3; ++k) items += (k ? ", " : "") + (k == i ? std::string("VALUE") : ok);
      out.push_back({"probelight", "object:\n  " + vector + ": " + items + "]\n", "object." + vector});
    }
  // camera.yaml: each element of the matrix and of the distortion.
  const std::string matrix_values[9] = {"627.0", "0.", "319.5", "0.", "627.0", "239.5", "0.", "0.", "1."};
  const std::string distortion_values[5] = {"0.02", "-0.05", "0.", "0.", "0."};
  auto camera_yaml = [&](int matrix_bad, int distortion_bad) {
    std::string m, d;
    for (int i = 0; i < 9; ++i) m += (i ? ", " : "") + (i == matrix_bad ? std::string("VALUE") : matrix_values[i]);
    for (int i = 0; i < 5; ++i) d += (i ? ", " : "") + (i == distortion_bad ? std::string("VALUE") : distortion_values[i]);
    return "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\ncamera_matrix: !!opencv-matrix\n   rows: 3\n"
           "   cols: 3\n   dt: d\n   data: [ " + m + " ]\ndistortion_coefficients: !!opencv-matrix\n   rows: 1\n"
           "   cols: 5\n   dt: d\n   data: [ " + d + " ]\n";
  };
  for (int i = 0; i < 9; ++i) out.push_back({"camera", camera_yaml(i, -1), "camera_matrix"});
  for (int i = 0; i < 5; ++i) out.push_back({"camera", camera_yaml(-1, i), "distortion_coefficients"});
  // rig.yaml.
  auto rig_yaml = [](const std::string& tag_size, const std::string& centre, const std::string& radius,
                     const std::string& reflectance) {
    return "%YAML:1.0\n---\ntag_family: tag36h11\ntag_id: 0\ntag_size: " + tag_size + "\nprobe_center: " + centre +
           "\nprobe_radius: " + radius + "\nprobe_reflectance: " + reflectance + "\n";
  };
  out.push_back({"rig", rig_yaml("VALUE", "[0.12, 0.0, 0.08]", "0.03", "0.7"), "tag_size"});
  out.push_back({"rig", rig_yaml("0.1", "[VALUE, 0.0, 0.08]", "0.03", "0.7"), "probe_center"});
  out.push_back({"rig", rig_yaml("0.1", "[0.12, VALUE, 0.08]", "0.03", "0.7"), "probe_center"});
  out.push_back({"rig", rig_yaml("0.1", "[0.12, 0.0, VALUE]", "0.03", "0.7"), "probe_center"});
  out.push_back({"rig", rig_yaml("0.1", "[0.12, 0.0, 0.08]", "VALUE", "0.7"), "probe_radius"});
  out.push_back({"rig", rig_yaml("0.1", "[0.12, 0.0, 0.08]", "0.03", "VALUE"), "probe_reflectance"});
  out.push_back({"rig", rig_yaml("0.1", "[0.12, 0.0, 0.08]", "0.03", "0.7") + "tag_white_albedo: VALUE\n",
                 "tag_white_albedo"});
  for (const std::string field : {"post_radius", "post_albedo"})
    out.push_back({"rig", rig_yaml("0.1", "[0.12, 0.0, 0.08]", "0.03", "0.7") + field + ": VALUE\n", field});
  return out;
}

TEST_F(Stress, NanOrInfInAnyFloatFieldIsOneLineAndExit2) {
  const std::vector<BadField> fields = badFields();
  ASSERT_EQ(fields.size(), 22u + 4u + 3u + 6u + 14u + 9u);
  for (const BadField& bad : fields) {
    for (const char* value : {".nan", ".inf", "-.inf"}) {
      std::string yaml = bad.yaml;
      yaml.replace(yaml.find("VALUE"), 5, value);
      const fs::path file = dir_ / (bad.file + ".yaml");
      writeText(file, yaml);
      const std::string flag = bad.file == "probelight" ? "--config" : bad.file == "camera" ? "--calibration" : "--" + bad.file;
      const CommandResult result = run("run --source sim --display headless --frames 1 " + flag + " " +
                                       file.string() + " --out " + (dir_ / "out").string());
      const std::string context = bad.file + ".yaml " + bad.field + " = " + value + ": " + result.stderr_text;
      EXPECT_EQ(result.exit_status, 2) << context;
      EXPECT_EQ(lineCount(result.stderr_text), 1) << context;
      EXPECT_NE(result.stderr_text.find(bad.field), std::string::npos) << context;
      EXPECT_FALSE(fs::exists(dir_ / "out" / "report.json")) << context;
    }
  }
}

}  // namespace
}  // namespace probelight
