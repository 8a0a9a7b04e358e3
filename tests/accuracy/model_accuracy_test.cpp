// Issue 16's accuracy table: a user's model as `probelight render` puts it
// into a simulated frame (its materials lit from the frame's 8-bit maps,
// its self-shadow and ground shadow from the fitted dome), against the
// simulator's path-traced copy of the same model in the same place
// (sim::meshOccluder: its own triangle tracer and glTF BRDF, self-occlusion,
// interreflection and the shadowed floor), in 5 worlds, both real HDR maps
// among them.
//
// Two truths: lit by what the 8-bit camera can know through the ball (each
// radiance clipped as the ball's camera clips it; the bound holds against
// this one, since light past the clip is not in an 8-bit frame), and by the
// full HDR world (reported, with and without an exposure bracket given to
// `render`).
//
// The figure: over the model's pixels (2 px inside its outline, so the
// anti-aliased edge is not counted), in 3 x 3 tiles, the relative
// difference of the tiles' mean linear luminance, averaged. A tile is the
// unit because the truth is Monte Carlo: 128 paths a pixel corner leave
// each pixel a few percent of noise, which an absolute difference would
// add to the error; 9 pixels cut it three-fold. Tiles the truth clips (a
// code of 250 or more) say nothing about the light and are left out.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "accuracy_test_support.hpp"
#include "app/analyze.hpp"
#include "app/command_line.hpp"
#include "config/camera_file.hpp"
#include "config/rig_file.hpp"
#include "core/math_constants.hpp"
#include "ibl/camera_projection.hpp"
#include "ibl/color_transfer.hpp"
#include "model/generated_models.hpp"
#include "model/gltf_loader.hpp"
#include "model/model_placement.hpp"
#include "sim/occluder.hpp"
#include "sim/scene_config.hpp"
#include "sim/scene_geometry.hpp"
#include "sim/world.hpp"
#include "stages/scene_object.hpp"

namespace probelight {
namespace {

namespace fs = std::filesystem;

constexpr int kTile = 3;
constexpr int kTruthClipCode = 250;

using testing::luminance;

double linearLuminanceAt(const ImageRGB8& image, int x, int y) {
  const std::uint8_t* p = image.row(y) + 3 * x;
  return luminance({ibl::srgbToLinear(p[0] / 255.0), ibl::srgbToLinear(p[1] / 255.0), ibl::srgbToLinear(p[2] / 255.0)});
}

struct World {
  std::string name;
  std::string environment;
};

std::vector<World> worlds() {
  const std::string data = PROBELIGHT_TEST_DATA_DIR;
  return {{"sun_sky", "sun_sky"},
          {"overcast", "overcast"},
          {"studio", "studio"},
          {"Kerner (real)", data + "/env/KernerEnvLatLong.exr"},
          {"Stage (real)", data + "/env/StageEnvLatLong.exr"}};
}

struct PlacedModel {
  std::string name;
  std::shared_ptr<const model::MeshModel> mesh;
  model::ModelPlacement placement;
};

// Beside the tag on the side away from the ball, as the other object
// figures: `size_m` its largest extent.
PlacedModel place(std::string name, std::shared_ptr<const model::MeshModel> mesh, double size_m, double yaw_deg) {
  PlacedModel placed{std::move(name), std::move(mesh), {}};
  placed.placement.position_m = {-0.10, 0.06};
  placed.placement.yaw_rad = glm::radians(yaw_deg);
  const glm::vec3 extent = placed.mesh->max_m - placed.mesh->min_m;
  placed.placement.scale = size_m / std::max({extent.x, extent.y, extent.z});
  return placed;
}

model::Material material(double base, double metallic, double roughness) {
  model::Material m;
  m.base_color_factor = glm::vec4(glm::vec3(static_cast<float>(base)), 1.0f);
  m.metallic_factor = static_cast<float>(metallic);
  m.roughness_factor = static_cast<float>(roughness);
  return m;
}

// One world's frame as the kiosk sees it (noise included), and the
// shorter exposures a bracket would add while the ball clips.
struct Inputs {
  sim::SceneConfig scene;
  ImageRGB8 frame;
  std::vector<std::pair<ImageRGB8, double>> bracket;  // frame, EV
};

Inputs inputsFor(const World& world) {
  Inputs inputs;
  inputs.scene = sim::defaultScene();
  inputs.scene.environment = world.environment;
  inputs.scene.camera_path.name = "static";
  const sim::World sim_world(inputs.scene);
  FrameTruth ignored;
  sim_world.render(0, inputs.frame, ignored);
  for (const double ev : {-3.0, -6.0, -9.0, -12.0}) {
    ImageRGB8 shorter;
    sim_world.render(0, shorter, ignored, ev);
    inputs.bracket.emplace_back(std::move(shorter), ev);
  }
  return inputs;
}

void writeRgb(const fs::path& path, const ImageRGB8& rgb) {
  cv::Mat bgr;
  cv::cvtColor(cv::Mat(rgb.height, rgb.width, CV_8UC3, const_cast<std::uint8_t*>(rgb.pixels.data())), bgr,
               cv::COLOR_RGB2BGR);
  ASSERT_TRUE(cv::imwrite(path.string(), bgr)) << path;
}

// What `render` is given to know the light past the 8-bit clip.
enum class Knowing {
  k8Bit,         // the frame alone, as it is (--no-white-ref --no-post-ref)
  kWhiteBorder,  // the frame alone, its clipped light restored from the tag's white border and the post (the default)
  kBracket,      // the frame and its bracket
};

// `probelight render` with the model (RenderOptions::model), as a user
// runs it on a kept frame: the composite it writes.
ImageRGB8 kioskComposite(const fs::path& dir, const Inputs& inputs, const PlacedModel& model, Knowing knowing,
                         bool self_shadow = true) {
  fs::create_directories(dir);
  writeRgb(dir / "frame.png", inputs.frame);
  config::saveCameraFile((dir / "camera.yaml").string(), inputs.scene.camera);
  config::saveRigFile((dir / "rig.yaml").string(), inputs.scene.rig);
  RenderOptions options;
  options.frame.frame_path = (dir / "frame.png").string();
  options.frame.camera_path = (dir / "camera.yaml").string();
  options.frame.rig_path = (dir / "rig.yaml").string();
  options.frame.out_dir = (dir / "out").string();
  if (!self_shadow) {
    std::FILE* config = std::fopen((dir / "probelight.yaml").c_str(), "w");
    std::fputs("object:\n  self_shadow: false\n", config);
    std::fclose(config);
    options.frame.config_path = (dir / "probelight.yaml").string();
  }
  options.frame.white_reference = options.frame.post_reference = knowing != Knowing::k8Bit;
  if (knowing == Knowing::kBracket)
    for (const auto& [frame, ev] : inputs.bracket) {
      const fs::path path = dir / ("ev" + std::to_string(static_cast<int>(ev)) + ".png");
      writeRgb(path, frame);
      options.frame.brackets.push_back({path.string(), ev});
    }
  options.object = "model";
  options.model = model.mesh;
  options.at_w = model.placement.position_m;
  options.yaw_deg = glm::degrees(model.placement.yaw_rad);
  options.scale = model.placement.scale;
  std::ostringstream log;
  const Status status = runRender(options, log);
  EXPECT_TRUE(status.isOk()) << status.message() << "\n" << log.str();
  const cv::Mat bgr = cv::imread((dir / "out" / "composite.png").string(), cv::IMREAD_COLOR);
  ImageRGB8 rgb;
  if (bgr.empty()) return rgb;
  rgb.resize(bgr.cols, bgr.rows);
  cv::Mat view(rgb.height, rgb.width, CV_8UC3, rgb.pixels.data());
  cv::cvtColor(bgr, view, cv::COLOR_BGR2RGB);
  return rgb;
}

// The model's pixels, seen from the frame's camera: the window its placed
// box projects to, and per pixel of it the surface the centre ray meets
// (through the simulator's tracer), kept where the whole 5 x 5 around it
// meets the model.
struct ModelPixels {
  sim::World::PixelWindow window;
  int width = 0;
  std::vector<std::uint8_t> inside;  // window-sized
  std::vector<glm::dvec3> point_w, normal_w;
  bool at(int x, int y) const {
    return x >= window.x_begin && x < window.x_end && y >= window.y_begin && y < window.y_end &&
           inside[static_cast<std::size_t>(y - window.y_begin) * width + (x - window.x_begin)];
  }
  std::size_t index(int x, int y) const { return static_cast<std::size_t>(y - window.y_begin) * width + (x - window.x_begin); }
};

ModelPixels modelPixels(const sim::SceneConfig& scene, const PoseCamFromWorld& pose, const sim::VirtualOccluder& mesh) {
  ModelPixels pixels;
  const sim::WorldBounds bounds = mesh.triangles->bounds();
  std::vector<glm::dvec3> corners;
  for (int k = 0; k < 8; ++k)
    corners.push_back({k & 1 ? bounds.max_w.x : bounds.min_w.x, k & 2 ? bounds.max_w.y : bounds.min_w.y,
                       k & 4 ? bounds.max_w.z : bounds.min_w.z});
  sim::World::PixelWindow& w = pixels.window;
  w = {scene.camera.width_px, scene.camera.height_px, 0, 0, true};
  for (const glm::dvec2& p : sim::projectWorldPoints(scene.camera, pose, corners)) {
    w.x_begin = std::min(w.x_begin, static_cast<int>(std::floor(p.x)) - 3);
    w.y_begin = std::min(w.y_begin, static_cast<int>(std::floor(p.y)) - 3);
    w.x_end = std::max(w.x_end, static_cast<int>(std::ceil(p.x)) + 4);
    w.y_end = std::max(w.y_end, static_cast<int>(std::ceil(p.y)) + 4);
  }
  w.x_begin = std::max(w.x_begin, 0);
  w.y_begin = std::max(w.y_begin, 0);
  w.x_end = std::min(w.x_end, scene.camera.width_px);
  w.y_end = std::min(w.y_end, scene.camera.height_px);
  pixels.width = w.x_end - w.x_begin;
  const std::size_t count = static_cast<std::size_t>(pixels.width) * (w.y_end - w.y_begin);
  std::vector<std::uint8_t> hit(count, 0);
  pixels.point_w.assign(count, glm::dvec3(0.0));
  pixels.normal_w.assign(count, glm::dvec3(0.0));
  const glm::dvec3 eye = pose.cameraCenterWorld();
  const glm::dmat3 world_from_cam = glm::transpose(pose.R_cam_from_world);
  for (int y = w.y_begin; y < w.y_end; ++y)
    for (int x = w.x_begin; x < w.x_end; ++x) {
      const glm::dvec3 dir = glm::normalize(world_from_cam * ibl::pixelToCameraRay(scene.camera, {x, y}));
      if (const std::optional<sim::TriangleHit> h = sim::intersectMesh(mesh, eye, dir, 10.0)) {
        const std::size_t i = pixels.index(x, y);
        hit[i] = 1;
        pixels.point_w[i] = eye + h->t * dir;
        pixels.normal_w[i] = h->back_face ? -h->shading_normal : h->shading_normal;
      }
    }
  pixels.inside.assign(count, 0);
  for (int y = w.y_begin + 2; y < w.y_end - 2; ++y)
    for (int x = w.x_begin + 2; x < w.x_end - 2; ++x) {
      bool all = true;
      for (int dy = -2; dy <= 2 && all; ++dy)
        for (int dx = -2; dx <= 2 && all; ++dx) all = hit[pixels.index(x + dx, y + dy)] != 0;
      pixels.inside[pixels.index(x, y)] = all ? 1 : 0;
    }
  return pixels;
}

// The relative error of `drawn` against `truth` over the model's tiles,
// and split by the way the surface faces (up: n.z > 0.4, down: < -0.4).
struct TileError {
  double mean = 0.0, up = 0.0, side = 0.0, down = 0.0, signed_mean = 0.0, signed_up = 0.0, signed_side = 0.0;
  int tiles = 0, up_tiles = 0, side_tiles = 0, down_tiles = 0, clipped_tiles = 0;
};

// `select`: which tiles count (by their centre pixel); all by default.
template <typename Select>
TileError tileError(const ImageRGB8& drawn, const ImageRGB8& truth, const ModelPixels& pixels, Select select) {
  TileError e;
  const sim::World::PixelWindow& w = pixels.window;
  for (int y0 = w.y_begin; y0 + kTile <= w.y_end; y0 += kTile)
    for (int x0 = w.x_begin; x0 + kTile <= w.x_end; x0 += kTile) {
      bool all = true, clipped = false;
      double d = 0.0, t = 0.0;
      for (int y = y0; y < y0 + kTile; ++y)
        for (int x = x0; x < x0 + kTile; ++x) {
          all = all && pixels.at(x, y);
          if (!all) break;
          const std::uint8_t* p = truth.row(y) + 3 * x;
          clipped = clipped || std::max({p[0], p[1], p[2]}) >= kTruthClipCode;
          d += linearLuminanceAt(drawn, x, y);
          t += linearLuminanceAt(truth, x, y);
        }
      if (!all) continue;
      const std::size_t centre = pixels.index(x0 + kTile / 2, y0 + kTile / 2);
      if (!select(centre)) continue;
      if (clipped) {
        ++e.clipped_tiles;
        continue;
      }
      if (!(t > 0.0)) continue;
      const double relative = (d - t) / t;
      e.mean += std::abs(relative);
      e.signed_mean += relative;
      ++e.tiles;
      const double nz = pixels.normal_w[centre].z;
      if (nz > 0.4) {
        e.up += std::abs(relative);
        e.signed_up += relative;
        ++e.up_tiles;
      } else if (nz < -0.4) {
        e.down += std::abs(relative);
        ++e.down_tiles;
      } else {
        e.side += std::abs(relative);
        e.signed_side += relative;
        ++e.side_tiles;
      }
    }
  if (e.tiles) {
    e.mean /= e.tiles;
    e.signed_mean /= e.tiles;
  }
  if (e.up_tiles) {
    e.up /= e.up_tiles;
    e.signed_up /= e.up_tiles;
  }
  if (e.side_tiles) {
    e.side /= e.side_tiles;
    e.signed_side /= e.side_tiles;
  }
  if (e.down_tiles) e.down /= e.down_tiles;
  return e;
}

TileError tileError(const ImageRGB8& drawn, const ImageRGB8& truth, const ModelPixels& pixels) {
  return tileError(drawn, truth, pixels, [](std::size_t) { return true; });
}

// With PROBELIGHT_ACCURACY_DUMP=DIR: the kiosk's model and the truth's side
// by side, 4x, for a look (the figures say how far apart, not where).
void dumpSideBySide(std::string name, const ImageRGB8& drawn, const ImageRGB8& truth, const ModelPixels& pixels) {
  const char* dump = std::getenv("PROBELIGHT_ACCURACY_DUMP");
  if (!dump) return;
  const sim::World::PixelWindow& w = pixels.window;
  const cv::Rect box(w.x_begin, w.y_begin, w.x_end - w.x_begin, w.y_end - w.y_begin);
  auto crop = [&](const ImageRGB8& image) {
    cv::Mat bgr;
    cv::cvtColor(cv::Mat(image.height, image.width, CV_8UC3, const_cast<std::uint8_t*>(image.pixels.data()))(box), bgr,
                 cv::COLOR_RGB2BGR);
    cv::resize(bgr, bgr, {}, 4, 4, cv::INTER_NEAREST);
    return bgr;
  };
  cv::Mat both;
  cv::hconcat(crop(drawn), crop(truth), both);
  std::replace_if(name.begin(), name.end(), [](char ch) { return !std::isalnum(static_cast<unsigned char>(ch)); }, '_');
  cv::imwrite((fs::path(dump) / (name + ".png")).string(), both);
}

// The simulator's frame of the model (its pixels only): lit by the
// 8-bit-knowable world or the full HDR one.
ImageRGB8 truthFrame(const sim::World& world, sim::VirtualOccluder mesh, const ModelPixels& pixels, bool clipped,
                     int max_bounces = 4) {
  mesh.clipped_lighting = clipped;
  mesh.path_samples = 128;
  mesh.max_bounces = max_bounces;
  ImageRGB8 frame;
  FrameTruth ignored;
  world.renderWithOccluders(0, {mesh}, frame, ignored, &pixels.window);
  return frame;
}

sim::SceneConfig noiseless(sim::SceneConfig scene) {
  scene.noise_sigma_code = 0.0;
  return scene;
}

// The models of the table, each with issue 16's bound on its mean over
// the worlds against the 8-bit-knowable truth: one test each (one is a
// minute and a half under the sanitizers).
struct ModelCase {
  const char* name;
  double bound;
};
void PrintTo(const ModelCase& c, std::ostream* os) { *os << c.name; }
const ModelCase kModelCases[] = {
    {"diffuse sphere mesh", 0.05}, {"BoxTextured", 0.05}, {"rough metal (0.3)", 0.10}, {"smooth metal (0.05)", 0.10}};

PlacedModel placedModel(const std::string& name) {
  auto sphere = [](double base, double metallic, double roughness) {
    return std::make_shared<const model::MeshModel>(model::sphereModel(1.0, 32, material(base, metallic, roughness)));
  };
  if (name == "diffuse sphere mesh") return place(name, sphere(0.2, 0.0, 1.0), 0.07, 0.0);
  if (name == "rough metal (0.3)") return place(name, sphere(0.5, 1.0, 0.3), 0.07, 0.0);
  if (name == "smooth metal (0.05)") return place(name, sphere(0.5, 1.0, 0.05), 0.07, 0.0);
  auto box_textured = std::make_shared<model::MeshModel>();
  std::string error;
  EXPECT_TRUE(model::loadGltfModel("/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf", {},
                                   *box_textured, error))
      << error;
  return place(name, box_textured, 0.06, 25.0);
}

class ModelAccuracy : public ::testing::TestWithParam<ModelCase> {};

TEST_P(ModelAccuracy, AgainstThePathTracedTruth) {
  const ModelCase& c = GetParam();
  const PlacedModel model = placedModel(c.name);
  ASSERT_FALSE(model.mesh->primitives.empty());
  const fs::path dir = fs::temp_directory_path() / ("probelight_model_accuracy_" + std::to_string(::getpid()));
  std::printf("\n| world | model | tiles (clipped) | vs 8-bit-knowable: mean (up / side / down), signed (up / side) "
              "| vs HDR: white border | vs HDR: bracket |\n|---|---|---|---|---|---|\n");
  double sum_clipped = 0.0, sum_border = 0.0, sum_bracket = 0.0;
  int n = 0;
  for (const World& world : worlds()) {
    const Inputs inputs = inputsFor(world);
    const sim::World truth_world(noiseless(inputs.scene));
    const SceneObject placed = modelSceneObject(model.mesh, model.placement);
    const sim::VirtualOccluder mesh = sim::meshOccluder(model.mesh, placed.world_from_model);
    const ModelPixels pixels = modelPixels(inputs.scene, truth_world.pose(0), mesh);
    const ImageRGB8 drawn = kioskComposite(dir / "8bit", inputs, model, Knowing::k8Bit);
    const ImageRGB8 drawn_border = kioskComposite(dir / "border", inputs, model, Knowing::kWhiteBorder);
    const ImageRGB8 drawn_bracket = kioskComposite(dir / "bracket", inputs, model, Knowing::kBracket);
    ASSERT_FALSE(drawn.empty() || drawn_border.empty() || drawn_bracket.empty());
    const ImageRGB8 truth_clipped = truthFrame(truth_world, mesh, pixels, true);
    const ImageRGB8 truth_hdr = truthFrame(truth_world, mesh, pixels, false);
    dumpSideBySide(world.name + "_" + c.name, drawn, truth_clipped, pixels);
    const TileError clipped = tileError(drawn, truth_clipped, pixels);
    const TileError border = tileError(drawn_border, truth_hdr, pixels);
    const TileError bracket = tileError(drawn_bracket, truth_hdr, pixels);
    std::printf("| %s | %s | %d (%d) | %.1f%% (%.1f / %.1f / %.1f), signed %+.1f%% (%+.1f / %+.1f) | %.1f%% | %.1f%% |\n",
                world.name.c_str(), c.name, clipped.tiles, clipped.clipped_tiles, 100 * clipped.mean, 100 * clipped.up,
                100 * clipped.side, 100 * clipped.down, 100 * clipped.signed_mean, 100 * clipped.signed_up,
                100 * clipped.signed_side, 100 * border.mean, 100 * bracket.mean);
    std::fflush(stdout);
    EXPECT_GT(clipped.tiles, 30) << world.name;
    sum_clipped += clipped.mean;
    sum_border += border.mean;
    sum_bracket += bracket.mean;
    ++n;
  }
  if (!std::getenv("PROBELIGHT_ACCURACY_DUMP")) fs::remove_all(dir);
  ASSERT_EQ(n, 5);
  std::printf("\n| model | vs 8-bit-knowable | bound | vs HDR: white border | vs HDR: bracket |\n|---|---|---|---|---|\n"
              "| %s | %.1f%% | %.0f%% | %.1f%% | %.1f%% |\n",
              c.name, 100 * sum_clipped / n, 100 * c.bound, 100 * sum_border / n, 100 * sum_bracket / n);
  EXPECT_LE(sum_clipped / n, c.bound);
}

INSTANTIATE_TEST_SUITE_P(Models, ModelAccuracy, ::testing::ValuesIn(kModelCases), [](const auto& info) {
  std::string name = info.param.name;
  name.erase(std::remove_if(name.begin(), name.end(), [](char ch) { return !std::isalnum(static_cast<unsigned char>(ch)); }),
             name.end());
  return name;
});

// The share of a surface point's cosine-weighted hemisphere that the model
// itself hides: a geometric measure of how shadowed a point can be by its
// own model, whatever the light (stratified over 16 x 16 directions).
double selfHiddenShare(const sim::VirtualOccluder& mesh, const glm::dvec3& point_w, const glm::dvec3& normal_w) {
  const glm::dvec3 helper = std::abs(normal_w.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0);
  const glm::dvec3 t = glm::normalize(glm::cross(helper, normal_w)), b = glm::cross(normal_w, t);
  constexpr int kSide = 16;
  int hidden = 0;
  for (int i = 0; i < kSide; ++i)
    for (int j = 0; j < kSide; ++j) {
      // Cosine-weighted (Malley): a uniform point of the disc lifted to the hemisphere.
      const double r = std::sqrt((i + 0.5) / kSide), phi = 2.0 * kPi * (j + 0.5) / kSide;
      const glm::dvec3 dir = r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(1.0 - r * r) * normal_w;
      hidden += sim::occluderBlocks(mesh, point_w + 1e-6 * normal_w, dir) ? 1 : 0;
    }
  return static_cast<double>(hidden) / (kSide * kSide);
}

// Self-shadowing, on a concave model: a bowl whose inside its own rim and
// walls hide much of the sky from. In the tiles where the bowl hides a
// quarter or more of a point's cosine-weighted hemisphere, the kiosk's
// error against the truth lit by the 8-bit-knowable world, with its
// self-shadow and without (object.self_shadow: false). The truth holds the
// light the bowl bounces onto itself, which the kiosk does not: a truth
// without interreflection (max_bounces 0) says how much of what remains
// is that.
TEST(ModelSelfShadowAccuracy, ABowlAgainstThePathTracedTruth) {
  const PlacedModel bowl =
      place("bowl", std::make_shared<const model::MeshModel>(model::bowlModel(0.5, 0.06, 16, material(0.6, 0.0, 0.8))),
            0.10, 0.0);
  const fs::path dir = fs::temp_directory_path() / ("probelight_bowl_accuracy_" + std::to_string(::getpid()));
  std::printf("\n| world | shadowed tiles (of all) | on | off | on, vs truth without interreflection | interreflection's share |\n"
              "|---|---|---|---|---|---|\n");
  double sum_on = 0.0, sum_off = 0.0, sum_on_direct = 0.0, sum_bounce = 0.0;
  int worlds_counted = 0;
  for (const World& world : worlds()) {
    const Inputs inputs = inputsFor(world);
    const sim::World truth_world(noiseless(inputs.scene));
    const SceneObject placed = modelSceneObject(bowl.mesh, bowl.placement);
    const sim::VirtualOccluder mesh = sim::meshOccluder(bowl.mesh, placed.world_from_model);
    const ModelPixels pixels = modelPixels(inputs.scene, truth_world.pose(0), mesh);
    std::vector<double> hidden(pixels.inside.size(), 0.0);
    for (std::size_t i = 0; i < hidden.size(); ++i)
      if (pixels.inside[i]) hidden[i] = selfHiddenShare(mesh, pixels.point_w[i], pixels.normal_w[i]);
    const auto shadowed = [&](std::size_t i) { return hidden[i] >= 0.25; };
    const ImageRGB8 on = kioskComposite(dir / "on", inputs, bowl, Knowing::k8Bit, true);
    const ImageRGB8 off = kioskComposite(dir / "off", inputs, bowl, Knowing::k8Bit, false);
    ASSERT_FALSE(on.empty() || off.empty());
    const ImageRGB8 truth = truthFrame(truth_world, mesh, pixels, true, 4);
    const ImageRGB8 truth_direct = truthFrame(truth_world, mesh, pixels, true, 0);
    dumpSideBySide(world.name + "_bowl_on", on, truth, pixels);
    dumpSideBySide(world.name + "_bowl_off", off, truth, pixels);
    const TileError e_on = tileError(on, truth, pixels, shadowed);
    const TileError e_off = tileError(off, truth, pixels, shadowed);
    const TileError e_on_direct = tileError(on, truth_direct, pixels, shadowed);
    const TileError bounce = tileError(truth_direct, truth, pixels, shadowed);
    const TileError all = tileError(on, truth, pixels);
    std::printf("| %s | %d (%d) | %.1f%% (signed %+.1f%%) | %.1f%% (signed %+.1f%%) | %.1f%% | %.1f%% |\n",
                world.name.c_str(), e_on.tiles, all.tiles, 100 * e_on.mean, 100 * e_on.signed_mean, 100 * e_off.mean,
                100 * e_off.signed_mean, 100 * e_on_direct.mean, 100 * -bounce.signed_mean);
    std::fflush(stdout);
    ASSERT_GT(e_on.tiles, 20) << world.name << ": the bowl's shadowed inside must be in view";
    // Without its self-shadow the bowl's hollow is too bright, in every
    // world; with it, never further off (a point of slack: in the overcast
    // world the two are within it, the self-shadow taking as much light
    // away as the missing interreflection would give back).
    EXPECT_GT(e_off.signed_mean, 0.0) << world.name;
    EXPECT_LT(e_on.mean, e_off.mean + 0.01) << world.name;
    sum_on += e_on.mean;
    sum_off += e_off.mean;
    sum_on_direct += e_on_direct.mean;
    sum_bounce += -bounce.signed_mean;
    ++worlds_counted;
  }
  if (!std::getenv("PROBELIGHT_ACCURACY_DUMP")) fs::remove_all(dir);
  const double n = worlds_counted;
  std::printf("\nmean over %d worlds, shadowed tiles: self-shadow on %.1f%%, off %.1f%%; on against the truth without "
              "interreflection %.1f%%; interreflection adds %.1f%% to the truth there\n",
              worlds_counted, 100 * sum_on / n, 100 * sum_off / n, 100 * sum_on_direct / n, 100 * sum_bounce / n);
  // "Falls clearly": the self-shadow takes away at least a third of the error.
  EXPECT_LT(sum_on / n, 0.67 * sum_off / n);
}

}  // namespace
}  // namespace probelight
