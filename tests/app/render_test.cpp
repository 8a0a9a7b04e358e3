// `probelight render`: a virtual object composited into one simulated frame,
// with its shadow on the real ground; and bad arguments.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binary_test_support.hpp"
#include "config/camera_file.hpp"
#include "config/rig_file.hpp"
#include "sim/scene_geometry.hpp"
#include "sim/world.hpp"

namespace probelight {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;

class Render : public testing::BinaryTest {
 protected:
  Render() : BinaryTest("render") {}

  // The default rig and orbit in the studio, frame 0; writes frame.png,
  // camera.yaml and rig.yaml; returns the flags naming them.
  std::string writeScene() {
    scene_ = sim::defaultScene();
    scene_.environment = "studio";
    scene_.rig.probe_reflectance = 0.7;
    const sim::World world(scene_);
    world.render(0, frame_, truth_);
    cv::Mat rgb(frame_.height, frame_.width, CV_8UC3, frame_.pixels.data()), bgr;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    EXPECT_TRUE(cv::imwrite((dir_ / "frame.png").string(), bgr));
    config::saveCameraFile((dir_ / "camera.yaml").string(), scene_.camera);
    config::saveRigFile((dir_ / "rig.yaml").string(), scene_.rig);
    return "render --frame " + (dir_ / "frame.png").string() + " --calibration " + (dir_ / "camera.yaml").string() +
           " --rig " + (dir_ / "rig.yaml").string() + " --out " + (dir_ / "out").string();
  }
  nlohmann::json readAnalysis() const {
    std::ifstream in(dir_ / "out" / "analysis.json");
    return nlohmann::json::parse(in);
  }
  cv::Mat composite() const { return cv::imread((dir_ / "out" / "composite.png").string(), cv::IMREAD_COLOR); }
  cv::Vec3b framePixel(int x, int y) const {
    const std::uint8_t* p = &frame_.pixels[(static_cast<std::size_t>(y) * frame_.width + x) * 3];
    return {p[2], p[1], p[0]};  // as BGR
  }

  sim::SceneConfig scene_;
  ImageRGB8 frame_;
  FrameTruth truth_;
};

TEST_F(Render, SphereBesideTheTagIsDrawnWithItsShadowAndEverythingElseUntouched) {
  const std::string base = writeScene();
  const glm::dvec2 at(-0.09, 0.07);
  const double radius = 0.03;
  // A dark sphere (albedo 0.05, the floor is 0.35): whatever the light, it
  // cannot come out the floor's colour, so "drawn" below is a real check.
  // (With 0.8 its centre was within 8 codes of the floor behind it.)
  const CommandResult result = run(base + " --object sphere --radius 0.03 --at -0.09,0.07 --albedo 0.05");
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  const cv::Mat image = composite();
  ASSERT_EQ(image.cols, frame_.width);
  ASSERT_EQ(image.rows, frame_.height);
  const nlohmann::json analysis = readAnalysis();
  ASSERT_EQ(analysis["lights"].size(), 8u);
  for (const auto& light : analysis["lights"]) {
    EXPECT_GE(light["direction"][2].get<double>(), 0.0);
    EXPECT_GE(light["rgb"][1].get<double>(), 0.0);
  }
  EXPECT_TRUE(analysis.contains("dominant_light"));
  EXPECT_GE(analysis["render"]["shadow"]["lights_casting"].get<int>(), 1);
  // The studio's soft boxes hide a good part of the light from the ground
  // right under the sphere.
  EXPECT_LT(analysis["render"]["shadow"]["darkest_fraction"].get<double>(), 0.5);

  // The sphere covers its projected outline (the simulator's own projection).
  const sim::ProbeOutline object = sim::probeOutline(scene_.camera, truth_.pose, glm::dvec3(at, radius), radius);
  const cv::Point centre(static_cast<int>(std::lround(object.center_px.x)), static_cast<int>(std::lround(object.center_px.y)));
  const cv::Vec3b drawn = image.at<cv::Vec3b>(centre), before = framePixel(centre.x, centre.y);
  EXPECT_GT(cv::norm(cv::Vec3i(drawn) - cv::Vec3i(before)), 10.0) << "nothing drawn at the sphere's centre";
  // Far from the object (beyond the square the shadows reach, and away from
  // the sphere), the frame is byte for byte the camera's.
  const double reach = analysis["render"]["shadow"]["region_half_size_m"].get<double>();
  int changed_far = 0, far = 0;
  for (int y = 0; y < image.rows; y += 3)
    for (int x = 0; x < image.cols; x += 3) {
      // Ground point under this pixel (undistorted ray onto z = 0).
      const glm::dvec3 ray_cam = glm::dvec3((x - scene_.camera.cx_px) / scene_.camera.fx_px,
                                            (y - scene_.camera.cy_px) / scene_.camera.fy_px, 1.0);
      const glm::dvec3 ray_w = glm::transpose(truth_.pose.R_cam_from_world) * ray_cam;
      const glm::dvec3 eye = truth_.pose.cameraCenterWorld();
      if (ray_w.z >= 0.0) continue;
      const glm::dvec2 ground = glm::dvec2(eye + (-eye.z / ray_w.z) * ray_w);
      // 20% beyond the square: distortion moves pixels by a few, not 20%.
      if (std::max(std::abs(ground.x - at.x), std::abs(ground.y - at.y)) < 1.2 * reach) continue;
      ++far;
      if (image.at<cv::Vec3b>(y, x) != framePixel(x, y)) ++changed_far;
    }
  EXPECT_GT(far, 100);
  EXPECT_EQ(changed_far, 0);
}

TEST_F(Render, BoxIsDrawnWhereItStands) {
  const std::string base = writeScene();
  const CommandResult result =
      run(base + " --object box --size 0.05,0.04,0.06 --yaw 30 --at -0.1,-0.04 --albedo 0.7,0.5,0.3");
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  const cv::Mat image = composite();
  ASSERT_FALSE(image.empty());
  // The box's middle (0.03 m up) projected: the box covers it.
  const std::vector<glm::dvec2> px = sim::projectWorldPoints(scene_.camera, truth_.pose, {{-0.1, -0.04, 0.03}});
  const cv::Point middle(static_cast<int>(std::lround(px[0].x)), static_cast<int>(std::lround(px[0].y)));
  const cv::Vec3b drawn = image.at<cv::Vec3b>(middle);
  EXPECT_GT(cv::norm(cv::Vec3i(drawn) - cv::Vec3i(framePixel(middle.x, middle.y))), 10.0);
  // Its albedo is orange-brown: red above green above blue (BGR order).
  EXPECT_GT(drawn[2], drawn[1]);
  EXPECT_GT(drawn[1], drawn[0]);
  const nlohmann::json analysis = readAnalysis();
  EXPECT_EQ(analysis["render"]["object"]["shape"], "box");
}

TEST_F(Render, BadArgumentsAreOneLineAndExit2) {
  const std::string base = writeScene();
  for (const std::string& bad :
       {std::string(" --object sphere"),                    // no radius
        std::string(" --object sphere --radius -1"),        // negative
        std::string(" --object sphere --radius 0.03 --at 1"),  // one coordinate
        std::string(" --object sphere --radius 0.03 --at 1,x"),
        std::string(" --object sphere --radius 0.03 --albedo 2"),
        std::string(" --object sphere --radius 0.03 --albedo 0.5,0.5"),
        std::string(" --object sphere --radius nan"),
        std::string(" --object cone --radius 0.03"),
        std::string(" --object box"),                       // no size
        std::string(" --object box --size 0.1,0,0.1"),
        std::string(" --object sphere --radius 0.03 --size 0.1,0.1,0.1")}) {
    const CommandResult result = run(base + bad);
    EXPECT_EQ(result.exit_status, 2) << bad << ": " << result.stderr_text;
    EXPECT_EQ(std::count(result.stderr_text.begin(), result.stderr_text.end(), '\n'), 1) << bad << ": " << result.stderr_text;
    EXPECT_FALSE(fs::exists(dir_ / "out" / "composite.png")) << bad;
  }
}

const std::string kCorpus = "/usr/share/assimp/models/glTF2/";

// The corpus's valid models (issue 16's list), scaled to a few cm: each is
// drawn where it stands (pixels between its foot and its top change), casts
// a shadow, and the report names the file and its triangles.
TEST_F(Render, CorpusModelsAreDrawnOnTheTagWithTheirShadow) {
  const std::string base = writeScene();
  struct Case {
    const char* file;
    double scale;  // to about 6 cm
  };
  for (const Case& c : {Case{"BoxTextured-glTF/BoxTextured.gltf", 0.06}, Case{"BoxTextured-glTF-Binary/BoxTextured.glb", 0.06},
                        Case{"BoxTextured-glTF-Embedded/BoxTextured.gltf", 0.06},
                        Case{"2CylinderEngine-glTF-Binary/2CylinderEngine.glb", 0.00009},
                        Case{"RecursiveNodes/RecursiveNodes.gltf", 0.01},
                        Case{"textureTransform/TextureTransformTest.gltf", 0.02},
                        Case{"BoxTexcoords-glTF/boxTexcoords.gltf", 0.06}}) {
    const std::string file = kCorpus + c.file;
    if (!fs::exists(file)) {
      ADD_FAILURE() << file << " is missing: install Debian's assimp-testmodels (scripts/install-deps.sh)";
      continue;
    }
    fs::remove_all(dir_ / "out");
    const CommandResult result = run(base + " --model " + file + " --scale " + std::to_string(c.scale) +
                                     " --yaw 30 --at -0.09,0.07");
    ASSERT_EQ(result.exit_status, 0) << file << ": " << result.stderr_text;
    const nlohmann::json analysis = readAnalysis();
    const nlohmann::json& object = analysis["render"]["object"];
    EXPECT_EQ(object["shape"], "model") << file;
    EXPECT_EQ(object["file"], file);
    if (std::string(c.file).rfind("RecursiveNodes", 0) == 0) {
      // Nodes that are their own ancestors and no mesh at all: it loads, with
      // the cycle said, and there is nothing to draw.
      EXPECT_EQ(object["triangles"].get<int>(), 0);
      EXPECT_FALSE(object["renderer"]["warnings"].empty());
      EXPECT_EQ(analysis["render"]["shadow"]["darkest_fraction"].get<double>(), 1.0);
      continue;
    }
    EXPECT_GT(object["triangles"].get<int>(), 0) << file;
    EXPECT_GE(analysis["render"]["shadow"]["lights_casting"].get<int>(), 1) << file;
    EXPECT_LT(analysis["render"]["shadow"]["darkest_fraction"].get<double>(), 0.9) << file << ": no shadow";
    // Drawn: many pixels around where it stands differ from the frame.
    const cv::Mat image = composite();
    ASSERT_FALSE(image.empty()) << file;
    const double radius = object["bounding_radius_m"].get<double>();
    const std::vector<glm::dvec2> px =
        sim::projectWorldPoints(scene_.camera, truth_.pose, {{-0.09, 0.07, 0.0}, {-0.09, 0.07, 2.0 * radius}});
    int changed = 0;
    const int x0 = static_cast<int>(std::min(px[0].x, px[1].x)) - 10, x1 = static_cast<int>(std::max(px[0].x, px[1].x)) + 10;
    const int y0 = static_cast<int>(std::min(px[0].y, px[1].y)), y1 = static_cast<int>(std::max(px[0].y, px[1].y));
    for (int y = std::max(0, y0); y <= std::min(image.rows - 1, y1); ++y)
      for (int x = std::max(0, x0); x <= std::min(image.cols - 1, x1); ++x)
        changed += cv::norm(cv::Vec3i(image.at<cv::Vec3b>(y, x)) - cv::Vec3i(framePixel(x, y))) > 6.0;
    EXPECT_GT(changed, 50) << file << ": nothing drawn where the model stands";
  }
}

// The corpus's broken files: one line naming the file, exit 2, no composite
// (issue 16's list; tests/model checks the loader's messages field by field).
TEST_F(Render, BrokenModelsAreOneLineAndExit2) {
  const std::string base = writeScene();
  for (const char* broken : {"IndexOutOfRange/IndexOutOfRange.gltf", "SchemaFailures/sceneWrongType.gltf",
                             "wrongTypes/badArray.gltf", "BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
                             "BoxBadNormals-glTF-Binary/BoxBadNormals.glb", "MissingBin/BoxTextured.gltf",
                             "IncorrectVertexArrays/Cube.gltf", "TestNoRootNode/NoScene.gltf"}) {
    const std::string file = kCorpus + broken;
    if (!fs::exists(file)) {
      ADD_FAILURE() << file << " is missing";
      continue;
    }
    fs::remove_all(dir_ / "out");
    const CommandResult result = run(base + " --model " + file);
    EXPECT_EQ(result.exit_status, 2) << file << ": " << result.stderr_text;
    EXPECT_EQ(std::count(result.stderr_text.begin(), result.stderr_text.end(), '\n'), 1) << result.stderr_text;
    EXPECT_NE(result.stderr_text.find(file), std::string::npos) << result.stderr_text;
    EXPECT_FALSE(fs::exists(dir_ / "out" / "composite.png")) << file;
  }
  // And the flags that do not go with a model.
  const std::string box = kCorpus + "BoxTextured-glTF/BoxTextured.gltf";
  for (const std::string& bad : {" --model " + box + " --object box --size 0.1,0.1,0.1", " --model " + box + " --radius 0.03",
                                 std::string(" --object sphere --radius 0.03 --scale 2"), " --model " + box + " --scale 0",
                                 std::string(" --model /nonexistent.glb")}) {
    const CommandResult result = run(base + bad);
    EXPECT_EQ(result.exit_status, 2) << bad << ": " << result.stderr_text;
    EXPECT_EQ(std::count(result.stderr_text.begin(), result.stderr_text.end(), '\n'), 1) << bad << ": " << result.stderr_text;
  }
}

// `run` shows the model probelight.yaml names (placed by its object
// section) in the simulated world, and its report says what was uploaded;
// --model overrides the file; a broken one stops the run before any frame.
TEST_F(Render, RunShowsTheConfiguredModel) {
  const fs::path config = dir_ / "probelight.yaml";
  {
    std::ofstream out(config);
    out << "object:\n  model: \"" << kCorpus << "BoxTextured-glTF/BoxTextured.gltf\"\n  scale: 0.05\n"
        << "  yaw: 20\n  position: [-0.09, 0.07, 0]\n";
  }
  const std::string base = "run --frames 6 --save-every 3 -q -c " + config.string() + " --out " + (dir_ / "run").string();
  CommandResult result = run(base);
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  nlohmann::json report;
  {
    std::ifstream in(dir_ / "run" / "report.json");
    report = nlohmann::json::parse(in);
  }
  EXPECT_EQ(report["model"]["triangles"], 12);
  EXPECT_EQ(report["model"]["textures"], 1);
  EXPECT_EQ(report["model"]["file"], kCorpus + "BoxTextured-glTF/BoxTextured.gltf");
  EXPECT_TRUE(fs::exists(dir_ / "run" / "frame_000003.png"));
  result = run(base + " --model " + kCorpus + "2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  {
    std::ifstream in(dir_ / "run" / "report.json");
    report = nlohmann::json::parse(in);
  }
  EXPECT_GT(report["model"]["triangles"].get<int>(), 100000);
  result = run(base + " --model " + kCorpus + "MissingBin/BoxTextured.gltf");
  EXPECT_EQ(result.exit_status, 2) << result.stderr_text;
  EXPECT_EQ(std::count(result.stderr_text.begin(), result.stderr_text.end(), '\n'), 1) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("MissingBin/BoxTextured.gltf"), std::string::npos) << result.stderr_text;
}

TEST_F(Render, FrameWithoutTagIsExit3AndNoComposite) {
  writeScene();
  cv::imwrite((dir_ / "grey.png").string(), cv::Mat(480, 640, CV_8UC3, cv::Scalar(120, 120, 120)));
  const CommandResult result =
      run("render --frame " + (dir_ / "grey.png").string() + " --calibration " + (dir_ / "camera.yaml").string() + " --rig " +
          (dir_ / "rig.yaml").string() + " --out " + (dir_ / "out").string() + " --object sphere --radius 0.03");
  EXPECT_EQ(result.exit_status, 3) << result.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "composite.png"));
  EXPECT_EQ(readAnalysis()["tag"]["status"], "no_tag");
}

}  // namespace
}  // namespace probelight
