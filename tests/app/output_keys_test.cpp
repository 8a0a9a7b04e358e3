// report.json and analysis.json keep every key they had: the key paths of a
// few runs and analyses, against the lists in tests/data/output-keys/ that
// were written by the binary before `run`, `analyze` and `render` were split
// into stages (issue 13). New keys may appear; none may go.
//
// A path is the object keys from the top joined by '.', with "[]" for the
// elements of an array (every element's keys, merged). Dynamic sections
// (counters, stages, skip reasons) are in the lists too: the simulated runs
// are deterministic, so the same events must still be counted under the same
// names.
//
// PROBELIGHT_WRITE_KEY_LISTS=DIR writes the lists seen into DIR instead of
// checking them (how the checked-in ones were made).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binary_test_support.hpp"
#include "config/camera_file.hpp"
#include "config/rig_file.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"

namespace probelight {
namespace {

namespace fs = std::filesystem;

const fs::path kKeyListDir = fs::path(PROBELIGHT_TEST_DATA_DIR) / "output-keys";

void collectKeyPaths(const nlohmann::json& value, const std::string& prefix, std::set<std::string>& out) {
  if (value.is_object()) {
    for (auto it = value.begin(); it != value.end(); ++it) {
      const std::string path = prefix.empty() ? it.key() : prefix + "." + it.key();
      out.insert(path);
      collectKeyPaths(*it, path, out);
    }
  } else if (value.is_array()) {
    for (const nlohmann::json& element : value) collectKeyPaths(element, prefix + "[]", out);
  }
}

std::set<std::string> keyPathsOf(const fs::path& json_file) {
  std::ifstream in(json_file);
  std::set<std::string> paths;
  collectKeyPaths(nlohmann::json::parse(in), "", paths);
  return paths;
}

class OutputKeys : public testing::BinaryTest {
 protected:
  OutputKeys() : BinaryTest("keys") {}

  // Every path of `list` is in `json_file`; or, with
  // PROBELIGHT_WRITE_KEY_LISTS, the file's paths are written as `list`.
  void expectKeysOf(const fs::path& json_file, const std::string& list) const {
    ASSERT_TRUE(fs::exists(json_file)) << json_file;
    const std::set<std::string> seen = keyPathsOf(json_file);
    if (const char* write_dir = std::getenv("PROBELIGHT_WRITE_KEY_LISTS")) {
      std::ofstream out(fs::path(write_dir) / list);
      for (const std::string& path : seen) out << path << "\n";
      return;
    }
    std::ifstream in(kKeyListDir / list);
    ASSERT_TRUE(in) << "missing " << (kKeyListDir / list);
    int expected = 0;
    for (std::string path; std::getline(in, path);) {
      if (path.empty()) continue;
      ++expected;
      EXPECT_TRUE(seen.count(path)) << fs::path(json_file).filename().string() << " lost the key " << path
                                    << " (" << list << ")";
    }
    EXPECT_GT(expected, 20) << list << " is too short to be a real list";
  }

  // frame.png, camera.yaml and rig.yaml of the simulator's default scene,
  // plus shorter exposures of the same view (under3.png, under6.png).
  std::string writeFrameAndBracket() const {
    const sim::SceneConfig scene = sim::defaultScene();
    const sim::World world(scene);
    auto write = [&](const std::string& name, double ev) {
      ImageRGB8 rgb;
      FrameTruth truth;
      world.render(0, rgb, truth, ev);
      cv::Mat bgr;
      cv::cvtColor(cv::Mat(rgb.height, rgb.width, CV_8UC3, rgb.pixels.data()), bgr, cv::COLOR_RGB2BGR);
      EXPECT_TRUE(cv::imwrite((dir_ / name).string(), bgr));
    };
    write("frame.png", 0.0);
    write("under3.png", -3.0);
    write("under6.png", -6.0);
    config::saveCameraFile((dir_ / "camera.yaml").string(), scene.camera);
    config::saveRigFile((dir_ / "rig.yaml").string(), scene.rig);
    return "--frame " + (dir_ / "frame.png").string() + " --calibration " + (dir_ / "camera.yaml").string() + " --rig " +
           (dir_ / "rig.yaml").string();
  }
};

TEST_F(OutputKeys, RunReportKeepsItsKeys) {
  // The default scene (studio, orbit): the start-up fit takes a bracket.
  const fs::path out = dir_ / "default";
  const auto result = run("run --source sim --frames 40 --save-every 0 --quiet --out " + out.string());
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  expectKeysOf(out / "report.json", "run_default.txt");

  // No bracket: the tag's white border and the ball's post restore the light.
  const fs::path config = dir_ / "no_bracket.yaml";
  std::ofstream(config) << "%YAML:1.0\n---\nlights:\n  bracket_max_stops: 0\n";
  const fs::path border = dir_ / "border";
  const auto bordered =
      run("run --source sim --frames 40 --save-every 0 --quiet --config " + config.string() + " --out " + border.string());
  ASSERT_EQ(bordered.exit_status, 0) << bordered.stderr_text;
  expectKeysOf(border / "report.json", "run_white_border.txt");
}

TEST_F(OutputKeys, AnalysisKeepsItsKeys) {
  const std::string inputs = writeFrameAndBracket();
  const auto plain = run("analyze " + inputs + " --out " + (dir_ / "plain").string());
  ASSERT_EQ(plain.exit_status, 0) << plain.stderr_text;
  expectKeysOf(dir_ / "plain" / "analysis.json", "analyze.txt");

  const auto bracketed = run("analyze " + inputs + " --bracket " + (dir_ / "under3.png").string() + "@-3 --bracket " +
                             (dir_ / "under6.png").string() + "@-6 --out " + (dir_ / "bracket").string());
  ASSERT_EQ(bracketed.exit_status, 0) << bracketed.stderr_text;
  expectKeysOf(dir_ / "bracket" / "analysis.json", "analyze_bracket.txt");

  const auto rendered =
      run("render " + inputs + " --object sphere --radius 0.03 --out " + (dir_ / "render").string());
  ASSERT_EQ(rendered.exit_status, 0) << rendered.stderr_text;
  expectKeysOf(dir_ / "render" / "analysis.json", "render.txt");
}

}  // namespace
}  // namespace probelight
