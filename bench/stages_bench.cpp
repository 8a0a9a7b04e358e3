// Milliseconds per pipeline stage against the stage's error, side by side in
// one run (docs/benchmarks.md has how to run it and what it measured).
//
// Set-up (outside every timed loop, done once on first use): a few frames of
// the default simulated scene with the "studio" environment, their truth, and
// one headless EGL context shared by every GL benchmark. Each benchmark
// computes its error counters once per configuration (cached, so repetitions
// and Google Benchmark's iteration-count probing do not redo them) and
// reports them as counters; the same numbers are printed as a plain table at
// the end, since the console reporter shows small counter values with SI
// prefixes (0.012 -> "12m").
//
// Map benchmarks use the simulator's true pose, so tracking error is not mixed
// into the map error; detect_pose measures the tracking error on its own.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <GLES2/gl2.h>
#include <benchmark/benchmark.h>
#include <glm/glm.hpp>

#include "capture/sim_frame_source.hpp"
#include "core/math_constants.hpp"
#include "core/types.hpp"
#include "core/ycbcr.hpp"
#include "gles/capabilities.hpp"
#include "gles/egl_context.hpp"
#include "gles/render_target.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/irradiance.hpp"
#include "ibl/spherical_harmonics.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/probe_accumulator.hpp"
#include "ibl/probe_observation.hpp"
#include "ibl/probe_outline.hpp"
#include "ibl/probe_to_cube.hpp"
#include "ibl/sensor_noise.hpp"
#include "stages/stage_settings.hpp"
#include "stages/probe_merge.hpp"
#include "ibl/ground_shadow.hpp"
#include "ibl/hdr_bracket.hpp"
#include "ibl/light_dome.hpp"
#include "ibl/spherical_blur.hpp"
#include "ibl/surface_shading.hpp"
#include "ibl/virtual_lamp.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "passes/ground_shadow.hpp"
#include "passes/object_bloom.hpp"
#include "passes/object_blur.hpp"
#include "passes/object_compositor.hpp"
#include "passes/virtual_lamp_light.hpp"
#include "sim/occluder.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"
#include "tracking/tag_tracker.hpp"

#include "stage_limits.hpp"

namespace probelight::bench {
namespace {

constexpr double kRadToDeg = 180.0 / kPi;

// Frames of the default orbit (-0.2 deg of azimuth per frame): 0, 12, 24 and
// 36 degrees round from the start, all with the tag and the ball in view.
constexpr std::uint64_t kFrameIndices[] = {0, 60, 120, 180};
// detect_pose/track runs over frames 0..29 in order, as the kiosk does.
constexpr std::uint64_t kConsecutiveFrames = 30;
// Reflection-map texels are compared with the truth only within this angle of
// the direction from the ball back toward the camera. Beyond it the ball
// shows directions only in a thin ring at its rim, where one camera pixel
// covers many degrees, and straight behind the ball (180 deg) is the blind
// spot it cannot show at all.
//
// The ground below the horizon is compared too, but it is near (0.05-0.15 m
// from a 0.03 m ball): the ball's surface points see it from up to 3 cm off
// the centre, while the truth is the view from the centre (the distant-light
// model every mirror-ball map assumes). That parallax alone costs 12-28% on
// the ground texels (more when the tag's black-and-white pattern is in the
// cone), whatever the face size, so err100_sky_pct (directions above the
// horizon) is reported as well: it is the stage's error on distant light, and
// the measure the kiosk's run report records (reflection_map_sky_rel_error).
constexpr double kMainConeDeg = 100.0;
constexpr double kNarrowConeDeg = 60.0;
// Normals for the diffuse map check: up and the four horizontals.
const glm::dvec3 kNormals[] = {{0, 0, 1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};

double luminance(const glm::dvec3& rgb) { return 0.2126 * rgb.r + 0.7152 * rgb.g + 0.0722 * rgb.b; }

struct Frame {
  std::uint64_t index = 0;
  ImageRGB8 rgb;
  FrameTruth truth;
  std::vector<std::uint8_t> luma;
  ibl::MirrorBallView view;  // true pose
  glm::dvec3 to_camera_w{0.0};
};

struct Setup {
  sim::SceneConfig scene;
  std::unique_ptr<sim::World> world;
  std::vector<Frame> frames;
  std::vector<Frame> consecutive_frames;  // 1 s of the orbit, for tracking from frame to frame
  std::unique_ptr<gles::EglContext> context;
  gles::Capabilities capabilities_full;
  gles::Capabilities capabilities_8bit;
  std::string gl_error;  // non-empty: no GL benchmarks
  // Clipped radiance truth per reflection face size, face-major like CubeMapRGB.
  std::map<int, std::vector<glm::dvec3>> radiance_truth;
  double irradiance_truth[5] = {};  // luminance of the clipped truth, per kNormals
  double irradiance_truth_hdr[5] = {};
};

Setup& setup() {
  static Setup* instance = [] {
    auto* s = new Setup;
    s->scene = sim::defaultScene();
    s->scene.environment = "studio";
    s->world = std::make_unique<sim::World>(s->scene);
    for (std::uint64_t index : kFrameIndices) {
      Frame frame;
      frame.index = index;
      s->world->render(index, frame.rgb, frame.truth);
      lumaFromRgb(frame.rgb, frame.luma);
      frame.view = ibl::MirrorBallView{s->scene.camera, frame.truth.pose, s->scene.rig.probe_center_w,
                                       s->scene.rig.probe_radius_m};
      frame.to_camera_w = glm::normalize(frame.truth.pose.cameraCenterWorld() - s->scene.rig.probe_center_w);
      std::fprintf(stderr, "setup: frame %llu: ball radius %.1f px, tag %s, ball %s\n",
                   static_cast<unsigned long long>(index), frame.truth.probe_radius_px,
                   frame.truth.tag_fully_visible ? "in view" : "NOT fully in view",
                   frame.truth.probe_fully_visible ? "in view" : "NOT fully in view");
      s->frames.push_back(std::move(frame));
    }
    for (std::uint64_t index = 0; index < kConsecutiveFrames; ++index) {
      Frame frame;
      frame.index = index;
      s->world->render(index, frame.rgb, frame.truth);
      lumaFromRgb(frame.rgb, frame.luma);
      s->consecutive_frames.push_back(std::move(frame));
    }
    std::fprintf(stderr, "setup: env %s, exposure %.4f (camera linear = radiance x exposure, clipped at 1)\n",
                 s->scene.environment.c_str(), s->world->exposure());
    // The scene has no lighting script, so every frame has the same lighting
    // state and one truth serves all frames.
    for (int i = 0; i < 5; ++i) {
      const sim::IrradianceTruth truth = s->world->irradiance(kNormals[i], 0);
      s->irradiance_truth[i] = luminance(truth.clipped);
      s->irradiance_truth_hdr[i] = luminance(truth.hdr);
    }
    s->context = gles::EglContext::createHeadless(s->gl_error);
    if (s->context) {
      s->capabilities_full = gles::probeCapabilities();
      s->capabilities_8bit = s->capabilities_full.withoutExtensions();
      std::fprintf(stderr, "setup: GL: %s (%s)\n", s->capabilities_full.summary().c_str(),
                   s->context->platformName().c_str());
    } else {
      std::fprintf(stderr, "setup: no GL context, GL benchmarks will be skipped: %s\n", s->gl_error.c_str());
    }
    return s;
  }();
  return *instance;
}

const std::vector<glm::dvec3>& radianceTruth(int face_size) {
  Setup& s = setup();
  auto found = s.radiance_truth.find(face_size);
  if (found != s.radiance_truth.end()) return found->second;
  std::vector<glm::dvec3> truth(static_cast<size_t>(ibl::kCubeFaceCount) * face_size * face_size);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (int y = 0; y < face_size; ++y)
      for (int x = 0; x < face_size; ++x)
        truth[(static_cast<size_t>(face) * face_size + y) * face_size + x] =
            s.world->radiance(ibl::cubeTexelCenterDirection(face, x, y, face_size), 0).clipped;
  return s.radiance_truth.emplace(face_size, std::move(truth)).first->second;
}

bool requireGl(benchmark::State& state) {
  Setup& s = setup();
  std::string error;
  if (!s.context) {
    state.SkipWithError(("no headless EGL context: " + s.gl_error).c_str());
    return false;
  }
  if (!s.context->makeCurrent(error)) {
    state.SkipWithError(error.c_str());
    return false;
  }
  return true;
}

// ---------------------------------------------------------------------------
// Error summaries, computed once per configuration and printed at the end.

struct ErrorRow {
  std::string name;
  std::vector<std::pair<std::string, double>> values;
};
std::map<std::string, ErrorRow>& errorTable() {
  static std::map<std::string, ErrorRow> table;
  return table;
}

// Returns the cached row, computing it on first use.
const ErrorRow& errorsFor(const std::string& name, const std::function<ErrorRow()>& compute) {
  auto& table = errorTable();
  auto found = table.find(name);
  if (found != table.end()) return found->second;
  ErrorRow row = compute();
  row.name = name;
  return table.emplace(name, std::move(row)).first->second;
}

void setCounters(benchmark::State& state, const ErrorRow& row) {
  for (const auto& [key, value] : row.values) state.counters[key] = value;
}

// ---------------------------------------------------------------------------
// 1. detect_pose

// Two ways the kiosk detects: "acquire" searches the whole frame (the first
// frame, after the tag was lost, and every 30th frame); "track" follows the
// tag from frame to frame and searches a window around where its motion
// predicts it (TagDetectorSettings::track_in_window). Acquire cycles through
// four far-apart orbit frames with the window off; track runs 30 consecutive
// frames and starts again from a full search at the wrap, so its median is
// the windowed cost and its mean includes the full searches.
enum class DetectMode { kAcquire, kTrack };

tracking::TagTracker makeTracker(int quad_decimate, int threads, DetectMode mode) {
  Setup& s = setup();
  tracking::TagDetectorSettings settings;
  settings.family = s.scene.rig.tag_family;
  settings.quad_decimate = static_cast<float>(quad_decimate);
  settings.nthreads = threads;
  settings.track_in_window = mode == DetectMode::kTrack;
  return tracking::TagTracker(settings, s.scene.rig, s.scene.camera);
}

void detectPose(benchmark::State& state, int quad_decimate, int threads, DetectMode mode) {
  Setup& s = setup();
  const std::string name = std::string("detect_pose/") + (mode == DetectMode::kTrack ? "track" : "acquire") +
                           "/decimate:" + std::to_string(quad_decimate) + "/threads:" + std::to_string(threads);
  const std::vector<Frame>& frames = mode == DetectMode::kTrack ? s.consecutive_frames : s.frames;
  auto trackFrame = [&](tracking::TagTracker& tracker, std::size_t i) {
    // Acquire: every frame stands alone. Track: history only within one pass.
    if (mode == DetectMode::kAcquire || i == 0) tracker.resetHistory();
    const Frame& frame = frames[i];
    return tracker.track(frame.luma.data(), frame.rgb.width, frame.rgb.height, frame.rgb.width);
  };
  // Errors: a fresh tracker over the frames in order, once.
  const ErrorRow& row = errorsFor(name, [&] {
    tracking::TagTracker tracker = makeTracker(quad_decimate, threads, mode);
    double rotation_sum = 0.0, translation_sum = 0.0, rotation_max = 0.0;
    int found = 0, windowed = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const tracking::TagTrackResult result = trackFrame(tracker, i);
      if (tracker.lastSearchWasWindowed()) ++windowed;
      if (!result.found) continue;
      ++found;
      const Frame& frame = frames[i];
      const double rotation =
          tracking::rotationDifferenceDeg(result.pose.R_cam_from_world, frame.truth.pose.R_cam_from_world);
      rotation_sum += rotation;
      rotation_max = std::max(rotation_max, rotation);
      translation_sum += 100.0 * glm::length(result.pose.t_cam_from_world - frame.truth.pose.t_cam_from_world) /
                         glm::length(frame.truth.pose.t_cam_from_world);
    }
    ErrorRow r;
    r.values = {{"rot_err_deg", found ? rotation_sum / found : NAN},
                {"rot_err_max_deg", rotation_max},
                {"trans_err_pct", found ? translation_sum / found : NAN},
                {"found_pct", 100.0 * found / static_cast<double>(frames.size())},
                {"windowed_pct", 100.0 * windowed / static_cast<double>(frames.size())}};
    return r;
  });
  tracking::TagTracker tracker = makeTracker(quad_decimate, threads, mode);
  size_t next = 0;
  for (auto _ : state) {
    tracking::TagTrackResult result = trackFrame(tracker, next);
    next = (next + 1) % frames.size();
    benchmark::DoNotOptimize(result);
  }
  setCounters(state, row);
}

// ---------------------------------------------------------------------------
// 2. probe_to_cube (GPU)

struct ReflectionErrors {
  double cone_main = 0.0;    // within kMainConeDeg of the camera side
  double cone_narrow = 0.0;  // within kNarrowConeDeg
  double all_valid = 0.0;    // every texel the stage marked valid (rim included)
  double sky = 0.0;          // main cone, directions above the horizon only (distant light)
  double valid_fraction = 0.0;
};

// sum |lum(map) - lum(truth)| / sum lum(truth), over texel sets.
ReflectionErrors compareReflection(const ibl::CubeMapRGB& map, const std::vector<float>& validity,
                                   const std::vector<glm::dvec3>& truth, const glm::dvec3& to_camera) {
  const double main_cos = std::cos(kMainConeDeg / kRadToDeg);
  const double narrow_cos = std::cos(kNarrowConeDeg / kRadToDeg);
  double abs_sky = 0, truth_sky = 0, abs_main = 0, truth_main = 0, abs_narrow = 0, truth_narrow = 0, abs_valid = 0, truth_valid = 0;
  size_t valid = 0, total = 0;
  const int n = map.face_size;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const size_t i = (static_cast<size_t>(face) * n + y) * n + x;
        const double estimated = luminance(glm::dvec3(map.texel(face, x, y)));
        const double expected = luminance(truth[i]);
        const double difference = std::abs(estimated - expected);
        const double cosine = glm::dot(ibl::cubeTexelCenterDirection(face, x, y, n), to_camera);
        ++total;
        if (validity[i] > 0.5f) {
          ++valid;
          abs_valid += difference;
          truth_valid += expected;
        }
        if (cosine >= main_cos) {
          abs_main += difference;
          truth_main += expected;
          if (ibl::cubeTexelCenterDirection(face, x, y, n).z >= 0.0) {
            abs_sky += difference;
            truth_sky += expected;
          }
        }
        if (cosine >= narrow_cos) {
          abs_narrow += difference;
          truth_narrow += expected;
        }
      }
    }
  }
  return {abs_main / truth_main, abs_narrow / truth_narrow, abs_valid / truth_valid, abs_sky / truth_sky,
          static_cast<double>(valid) / static_cast<double>(total)};
}

// Mean |lum(gpu) - lum(cpu)| / mean lum(cpu) within the main cone.
double compareWithCpu(const ibl::CubeMapRGB& gpu, const ibl::CubeMapRGB& cpu, const glm::dvec3& to_camera) {
  const double main_cos = std::cos(kMainConeDeg / kRadToDeg);
  double abs_sum = 0.0, cpu_sum = 0.0;
  const int n = gpu.face_size;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        if (glm::dot(ibl::cubeTexelCenterDirection(face, x, y, n), to_camera) < main_cos) continue;
        abs_sum += std::abs(luminance(glm::dvec3(gpu.texel(face, x, y))) - luminance(glm::dvec3(cpu.texel(face, x, y))));
        cpu_sum += luminance(glm::dvec3(cpu.texel(face, x, y)));
      }
  return abs_sum / cpu_sum;
}

const ibl::CubeMapRGB& cpuReflection(int face_size, int iterations) {
  static std::map<std::pair<int, int>, ibl::CubeMapRGB> cache;
  const auto key = std::make_pair(face_size, iterations);
  auto found = cache.find(key);
  if (found != cache.end()) return found->second;
  Setup& s = setup();
  ibl::ProbeToCubeParams params;
  params.face_size = face_size;
  params.normal_iterations = iterations;
  params.probe_reflectance = s.scene.rig.probe_reflectance;
  return cache.emplace(key, ibl::probeImageToCubeMap(s.frames[0].view, s.frames[0].rgb, params)).first->second;
}

// Camera frames as textures, one per frame, for one capability set.
struct FrameTextures {
  std::vector<std::unique_ptr<passes::CameraFrameTexture>> textures;
  bool init(const gles::Capabilities& capabilities, std::string& error) {
    for (const Frame& frame : setup().frames) {
      auto texture = std::make_unique<passes::CameraFrameTexture>();
      if (!texture->init(capabilities, error) || !texture->upload(frame.rgb, error)) return false;
      textures.push_back(std::move(texture));
    }
    return true;
  }
};

void probeToCube(benchmark::State& state, bool eight_bit, int face_size, int iterations) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  const gles::Capabilities& capabilities = eight_bit ? s.capabilities_8bit : s.capabilities_full;
  std::string error;
  FrameTextures frames;
  passes::EnvironmentMaps maps;
  passes::EnvironmentMapSettings settings;
  settings.reflection_face_size = face_size;
  settings.normal_iterations = iterations;
  if (!frames.init(capabilities, error) || !maps.init(capabilities, settings, error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  const std::string name = std::string("probe_to_cube/") + (eight_bit ? "8bit" : "half") +
                           "/face:" + std::to_string(face_size) + "/iters:" + std::to_string(iterations);
  bool failed = false;
  const ErrorRow& row = errorsFor(name, [&] {
    ErrorRow r;
    ReflectionErrors sum;
    double gpu_vs_cpu = NAN;
    for (size_t f = 0; f < s.frames.size(); ++f) {
      std::vector<float> validity;
      std::optional<ibl::CubeMapRGB> map;
      if (!maps.updateReflection(*frames.textures[f], s.frames[f].view, s.scene.rig.probe_reflectance, error) ||
          !(map = maps.readReflection(error, &validity))) {
        failed = true;
        return r;
      }
      const ReflectionErrors e = compareReflection(*map, validity, radianceTruth(face_size), s.frames[f].to_camera_w);
      sum.cone_main += e.cone_main;
      sum.cone_narrow += e.cone_narrow;
      sum.all_valid += e.all_valid;
      sum.sky += e.sky;
      sum.valid_fraction += e.valid_fraction;
      if (f == 0) gpu_vs_cpu = compareWithCpu(*map, cpuReflection(face_size, iterations), s.frames[0].to_camera_w);
    }
    const double count = static_cast<double>(s.frames.size());
    r.values = {{"err100_pct", 100.0 * sum.cone_main / count},
                {"err60_pct", 100.0 * sum.cone_narrow / count},
                {"err100_sky_pct", 100.0 * sum.sky / count},
                {"err_valid_pct", 100.0 * sum.all_valid / count},
                {"valid_pct", 100.0 * sum.valid_fraction / count},
                {"gpu_vs_cpu_pct", 100.0 * gpu_vs_cpu}};
    return r;
  });
  if (failed) {
    errorTable().erase(name);
    state.SkipWithError(error.c_str());
    return;
  }
  size_t next = 0;
  for (auto _ : state) {
    if (!maps.updateReflection(*frames.textures[next], s.frames[next].view, s.scene.rig.probe_reflectance, error)) {
      state.SkipWithError(error.c_str());
      break;
    }
    glFinish();
    next = (next + 1) % s.frames.size();
  }
  setCounters(state, row);
}

// The kiosk's merge as it runs at each map update (stages/maps_stage with
// environment_maps.merge_views): the reflection map just made read back,
// merged with the frame around the ball (stages/probe_merge), and the
// merged probe uploaded as the reflection map. The pass that made the map is
// probe_to_cube's row, left out here (timing paused, the GPU finished).
// Error: as probe_merge's rows, the merged probe as the GPU holds it.
void probeMergeKiosk(benchmark::State& state, bool eight_bit) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  const gles::Capabilities& capabilities = eight_bit ? s.capabilities_8bit : s.capabilities_full;
  constexpr int kFace = 64;
  std::string error;
  FrameTextures frames;
  passes::EnvironmentMaps maps;
  passes::EnvironmentMapSettings settings;
  settings.reflection_face_size = kFace;
  if (!frames.init(capabilities, error) || !maps.init(capabilities, settings, error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  RigGeometry rig = s.scene.rig;
  rig.post_radius_m = s.scene.post_radius_m;
  std::vector<FrameBuffer> pixels(s.frames.size());
  for (std::size_t f = 0; f < s.frames.size(); ++f) {
    pixels[f].rgb = s.frames[f].rgb;
    pixels[f].finishRgb();
  }
  // One map update's merge; false with `error` when the GPU failed.
  // Each part's time (the read-back, the merge, the upload), summed.
  double part_ms[3] = {0.0, 0.0, 0.0};
  auto mergeOne = [&](ProbeMerge& probe, std::size_t f) {
    using Clock = std::chrono::steady_clock;
    auto ms = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
    const Clock::time_point start = Clock::now();
    std::vector<float> validity;
    const std::optional<ibl::CubeMapRGB> map = maps.readReflection(error, &validity);
    if (!map) return false;
    const Clock::time_point read = Clock::now();
    probe.addView(s.frames[f].view, *map, &validity, nullptr, 1.0, &pixels[f]);
    const Clock::time_point merged = Clock::now();
    const std::vector<float> merged_validity = probe.validity();
    const bool uploaded = maps.setReflection(probe.liveMap(), error, &merged_validity);
    glFinish();
    part_ms[0] += ms(start, read);
    part_ms[1] += ms(read, merged);
    part_ms[2] += ms(merged, Clock::now());
    return uploaded;
  };
  const std::string name = std::string("probe_merge/kiosk/") + (eight_bit ? "8bit" : "half") + "/face:64";
  bool failed = false;
  const ErrorRow& row = errorsFor(name, [&] {
    ErrorRow r;
    ProbeMerge probe(ibl::CameraTransfer{}, rig, kFace);
    for (std::size_t f = 0; f < s.frames.size() && !failed; ++f)
      failed = !maps.updateReflection(*frames.textures[f], s.frames[f].view, rig.probe_reflectance, error) ||
               !mergeOne(probe, f);
    std::vector<float> validity;
    const std::optional<ibl::CubeMapRGB> held = failed ? std::nullopt : maps.readReflection(error, &validity);
    if (!held) {
      failed = true;
      return r;
    }
    double merged_error = 0.0;
    for (int i = 0; i < 5; ++i) {
      const double truth = s.irradiance_truth[i];
      merged_error += std::abs(luminance(ibl::irradianceFromCubeMap(*held, kNormals[i])) - truth) / truth / 5.0;
    }
    r.values = {{"merged_err_pct", 100.0 * merged_error}, {"seen_pct", 100.0 * probe.accumulator().seenSolidAngleFraction()}};
    return r;
  });
  if (failed) {
    errorTable().erase(name);
    state.SkipWithError(error.c_str());
    return;
  }
  ProbeMerge probe(ibl::CameraTransfer{}, rig, kFace);
  std::size_t next = 0;
  part_ms[0] = part_ms[1] = part_ms[2] = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    const bool made = maps.updateReflection(*frames.textures[next], s.frames[next].view, rig.probe_reflectance, error);
    glFinish();
    state.ResumeTiming();
    if (!made || !mergeOne(probe, next)) {
      state.SkipWithError(error.c_str());
      break;
    }
    next = (next + 1) % s.frames.size();
  }
  setCounters(state, row);
  const double iterations = std::max<double>(1.0, static_cast<double>(state.iterations()));
  state.counters["read_ms"] = part_ms[0] / iterations;
  state.counters["merge_ms"] = part_ms[1] / iterations;
  state.counters["upload_ms"] = part_ms[2] / iterations;
}

// ---------------------------------------------------------------------------
// 3. diffuse_blur (GPU cosine passes) and diffuse_sh9 (read-back, CPU
//    projection, GPU evaluation): the two diffuse methods side by side.

// One diffuse update by the chosen method.
bool updateDiffuseMap(passes::EnvironmentMaps& maps, bool sh9, std::string& error) {
  if (!sh9) return maps.updateDiffuse(error);
  std::vector<float> validity;
  const std::optional<ibl::CubeMapRGB> reflection = maps.readReflection(error, &validity);
  return reflection && maps.updateDiffuseFromSH9(ibl::projectToSH9(*reflection, &validity), error);
}

// The diffuse benchmarks' name: "face" is the diffuse map's size, "rows"
// the latitude-longitude maps' (after the east and north passes).
std::string diffuseName(bool eight_bit, int intermediate_rows, int face_size, int half_taps, bool sh9) {
  const std::string storage = eight_bit ? "8bit" : "half";
  if (sh9) return "diffuse_sh9/" + storage + "/face:" + std::to_string(face_size);
  return "diffuse_blur/" + storage + "/rows:" + std::to_string(intermediate_rows) + "/face:" +
         std::to_string(face_size) + "/half_taps:" + std::to_string(half_taps);
}

void diffuseBlur(benchmark::State& state, bool eight_bit, int intermediate_rows, int face_size, int half_taps,
                 bool sh9 = false) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  const gles::Capabilities& capabilities = eight_bit ? s.capabilities_8bit : s.capabilities_full;
  std::string error;
  FrameTextures frames;
  passes::EnvironmentMaps maps;
  passes::EnvironmentMapSettings settings;  // reflection 64, prefilter 16, 2 iterations
  settings.intermediate_rows = intermediate_rows;
  settings.diffuse_face_size = face_size;
  settings.blur_half_taps = half_taps;
  if (!frames.init(capabilities, error) || !maps.init(capabilities, settings, error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  const std::string name = diffuseName(eight_bit, intermediate_rows, face_size, half_taps, sh9);
  bool failed = false;
  const ErrorRow& row = errorsFor(name, [&] {
    ErrorRow r;
    double vs_truth = 0, vs_hdr = 0, vs_reflection = 0, probe_part = 0, worst = 0;
    int count = 0;
    for (size_t f = 0; f < s.frames.size(); ++f) {
      std::optional<ibl::CubeMapRGB> reflection, diffuse;
      if (!maps.updateReflection(*frames.textures[f], s.frames[f].view, s.scene.rig.probe_reflectance, error) ||
          !updateDiffuseMap(maps, sh9, error) || !(reflection = maps.readReflection(error)) ||
          !(diffuse = maps.readDiffuse(error))) {
        failed = true;
        return r;
      }
      for (int i = 0; i < 5; ++i) {
        const double estimated = kPi * luminance(glm::dvec3(diffuse->sampleBilinear(kNormals[i])));
        const double from_reflection = luminance(ibl::irradianceFromCubeMap(*reflection, kNormals[i]));
        const double truth = s.irradiance_truth[i];
        const double e = std::abs(estimated - truth) / truth;
        vs_truth += e;
        worst = std::max(worst, e);
        vs_hdr += std::abs(estimated - s.irradiance_truth_hdr[i]) / s.irradiance_truth_hdr[i];
        vs_reflection += std::abs(estimated - from_reflection) / from_reflection;
        probe_part += std::abs(from_reflection - truth) / truth;
        ++count;
      }
    }
    r.values = {{"err_vs_truth_pct", 100.0 * vs_truth / count},
                {"err_vs_truth_max_pct", 100.0 * worst},
                {"err_vs_hdr_pct", 100.0 * vs_hdr / count},
                {"blur_err_pct", 100.0 * vs_reflection / count},
                {"probe_part_pct", 100.0 * probe_part / count}};
    return r;
  });
  if (failed) {
    errorTable().erase(name);
    state.SkipWithError(error.c_str());
    return;
  }
  // The reflection map of frame 0 is the input of every timed pass.
  if (!maps.updateReflection(*frames.textures[0], s.frames[0].view, s.scene.rig.probe_reflectance, error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  glFinish();
  for (auto _ : state) {
    if (!updateDiffuseMap(maps, sh9, error)) {
      state.SkipWithError(error.c_str());
      break;
    }
    glFinish();
  }
  setCounters(state, row);
}

// ---------------------------------------------------------------------------
// 3b. lights and shadows: the dome fit (CPU, at a recalibration) and the
// shadow maps + ground fraction (GPU, when the lights or the object change),
// with the ground fraction's error against the simulator's brute-force truth
// of the clipped environment (World::groundShadow), for a 35 mm sphere
// beside the tag.

struct ShadowRig {
  FrameTextures frames;
  passes::EnvironmentMaps maps;
  std::optional<ibl::CubeMapRGB> reflection;
  std::vector<float> validity;
  bool init(std::string& error) {
    Setup& s = setup();
    if (!frames.init(s.capabilities_full, error) ||
        !maps.init(s.capabilities_full, passes::EnvironmentMapSettings{}, error) ||
        !maps.updateReflection(*frames.textures[0], s.frames[0].view, s.scene.rig.probe_reflectance, error))
      return false;
    reflection = maps.readReflection(error, &validity);
    return reflection.has_value();
  }
};

ibl::ShadowCaster benchCaster() {
  ibl::ShadowCaster caster;
  caster.position_w = {-0.10, 0.06};
  caster.radius_m = 0.035;
  return caster;
}

void fitLights(benchmark::State& state, ibl::DomePlacement placement, int count) {
  if (!requireGl(state)) return;
  ShadowRig rig;
  std::string error;
  if (!rig.init(error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  ibl::LightDomeSettings settings;
  settings.placement = placement;
  settings.light_count = count;
  for (auto _ : state) {
    std::vector<ibl::DomeLight> dome = ibl::fitLightDome(*rig.reflection, &rig.validity, settings);
    benchmark::DoNotOptimize(dome);
  }
}

void shadows(benchmark::State& state, ibl::DomePlacement placement, int count) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  ShadowRig rig;
  passes::GroundShadow shadow;
  std::string error;
  if (!rig.init(error) || !shadow.init(s.capabilities_full, {}, error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  ibl::LightDomeSettings settings;
  settings.placement = placement;
  settings.light_count = count;
  const std::vector<ibl::ShadowLight> lights =
      ibl::groundShadowLights(ibl::fitLightDome(*rig.reflection, &rig.validity, settings));
  const ibl::ShadowCaster caster = benchCaster();
  const std::string name = std::string("shadows/") + ibl::toString(placement) + "/lights:" + std::to_string(count);
  bool failed = false;
  const ErrorRow& row = errorsFor(name, [&] {
    ErrorRow r;
    std::optional<std::vector<glm::vec3>> fraction;
    if (!shadow.update(lights, caster, error) || !(fraction = shadow.readFraction(error))) {
      failed = true;
      return r;
    }
    // The ground around the sphere: 24 x 24 points over +-4 radii, outside it.
    std::vector<glm::dvec2> points;
    for (int j = 0; j < 24; ++j)
      for (int i = 0; i < 24; ++i) {
        const glm::dvec2 p = caster.position_w + 4.0 * caster.radius_m * glm::dvec2((2 * i + 1) / 24.0 - 1.0, (2 * j + 1) / 24.0 - 1.0);
        if (glm::length(p - caster.position_w) > caster.radius_m * 0.3) points.push_back(p);
      }
    sim::VirtualOccluder occluder;
    occluder.position_w = caster.position_w;
    occluder.radius_m = caster.radius_m;
    const std::vector<sim::World::GroundShadowTruth> truth = s.world->groundShadow(points, {occluder}, 0);
    const ibl::GroundRegion& region = shadow.region();
    const int n = shadow.groundTextureSizePx();
    double mae = 0.0;
    for (std::size_t k = 0; k < points.size(); ++k) {
      const glm::dvec2 uv = (points[k] - region.centre_w) / (2.0 * region.half_size_m) + 0.5;
      double ours = 1.0;
      if (uv.x >= 0.0 && uv.y >= 0.0 && uv.x < 1.0 && uv.y < 1.0) {
        const int i = static_cast<int>(uv.x * n), j = static_cast<int>(uv.y * n);
        ours = luminance(glm::dvec3((*fraction)[static_cast<std::size_t>(j) * n + i]));
      }
      mae += std::abs(ours - luminance(truth[k].clipped)) / points.size();
    }
    r.values = {{"mae_vs_clipped", mae}, {"lights_casting", static_cast<double>(lights.size())}};
    return r;
  });
  if (failed) {
    state.SkipWithError(error.c_str());
    return;
  }
  for (auto _ : state) {
    if (!shadow.update(lights, caster, error)) {
      state.SkipWithError(error.c_str());
      break;
    }
    glFinish();
  }
  setCounters(state, row);
}

// The per-frame cost of the shadow once it is made: the ground square drawn
// over the camera image.
void shadowComposite(benchmark::State& state) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  ShadowRig rig;
  passes::GroundShadow shadow;
  gles::RenderTarget target;
  std::string error;
  if (!rig.init(error) || !shadow.init(s.capabilities_full, {}, error) ||
      !shadow.update(ibl::groundShadowLights(ibl::fitLightDome(*rig.reflection, &rig.validity)), benchCaster(), error) ||
      !target.init(s.scene.camera.width_px, s.scene.camera.height_px, error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  target.bind();
  for (auto _ : state) {
    if (!shadow.drawOnCameraImage(s.scene.camera, s.frames[0].truth.pose, *rig.frames.textures[0], error)) {
      state.SkipWithError(error.c_str());
      break;
    }
    glFinish();
  }
}

// The virtual lamp over the frame once its shadow mask is made (the
// compose stage with virtual_lamp enabled, at its defaults: a point light
// 25 cm up beside the object): the whole-frame pass with the dome's
// shadow, and the detail pass about the object's shadow and the rig; these
// stand in for render's background and shadow_composite. With
// `smooth_only`, the whole-frame pass alone.
void virtualLampComposite(benchmark::State& state, bool smooth_only) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  ShadowRig rig;
  passes::GroundShadow shadow;
  passes::VirtualLampLight lamp_light;
  gles::RenderTarget target;
  std::string error;
  const ibl::VirtualLamp lamp;
  const ibl::ShadowCaster caster = benchCaster();
  std::vector<glm::vec3> caster_triangles = passes::casterTriangles(caster);
  if (!rig.init(error) || !shadow.init(s.capabilities_full, {}, error) ||
      !shadow.update(ibl::groundShadowLights(ibl::fitLightDome(*rig.reflection, &rig.validity)), caster, error) ||
      !lamp_light.init(s.capabilities_full, passes::VirtualLampLightSettings{}, s.scene.camera, error) ||
      !lamp_light.updateShadow(lamp, caster_triangles, error) ||
      !target.init(s.scene.camera.width_px, s.scene.camera.height_px, error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  passes::VirtualLampLight::Frame frame;
  frame.ratio_at_one_metre_rgb = ibl::lampRatioAtOneMetre(lamp, glm::dvec3(0.8, 0.75, 0.7));
  frame.dome_shadow = &shadow;
  const PoseCamFromWorld& pose = s.frames[0].truth.pose;
  const passes::CameraFrameTexture& camera_frame = *rig.frames.textures[0];
  target.bind();
  for (auto _ : state) {
    const bool drawn =
        lamp_light.drawSmooth(s.scene.camera, pose, camera_frame, s.scene.rig, frame, error) &&
        (smooth_only || lamp_light.drawDetail(s.scene.camera, pose, camera_frame, s.scene.rig, frame, error));
    if (!drawn) {
      state.SkipWithError(error.c_str());
      break;
    }
    glFinish();
  }
}

// ---------------------------------------------------------------------------
// 4. render + present readback, and the camera upload

struct RenderRig {
  FrameTextures frames;
  passes::EnvironmentMaps maps;
  passes::ObjectCompositor compositor;
  gles::RenderTarget target;
  bool init(std::string& error) {
    Setup& s = setup();
    return frames.init(s.capabilities_full, error) &&
           maps.init(s.capabilities_full, passes::EnvironmentMapSettings{}, error) &&
           compositor.init(s.capabilities_full, passes::ObjectCompositorSettings{}, maps.storage(), error) &&
           target.init(s.scene.camera.width_px, s.scene.camera.height_px, error) &&
           maps.updateReflection(*frames.textures[0], s.frames[0].view, s.scene.rig.probe_reflectance, error) &&
           maps.updateDiffuse(error);
  }
  // The app's defaults (AppSettings::object): a 35 mm sphere resting on the
  // tag; with `blur`, through it by blur_sigma_px (as the compose stage
  // with camera_match.blur), the noise then at its composite.
  passes::ObjectBlurLayer* blur = nullptr;
  double blur_sigma_px = 0.0;
  glm::dvec2 blur_smear_px{0.0};  // the camera's motion over the exposure (camera_match.motion_blur)
  const passes::SensorNoiseMatch* blur_noise = nullptr;
  const passes::SensorNoiseTexture* blur_noise_texture = nullptr;
  // With `bloom`, the sphere's light beyond white spread around it (the
  // compose stage with camera_match.bloom, when the bound says it can
  // exceed white): a bright pass of the sphere, then the glare's passes.
  passes::ObjectBloom* bloom = nullptr;
  bool draw(std::string& error) {
    Setup& s = setup();
    ibl::SurfaceMaterial material;
    material.albedo = glm::vec3(0.8f);
    material.k_specular = 0.25f;
    material.shininess = 48.0f;
    material.k_reflect = 0.08f;
    ibl::SceneLighting lighting;
    target.bind();
    compositor.drawCameraBackground(*frames.textures[0]);
    const glm::dvec3 centre(0.0, 0.0, 0.035);
    if (blur)
      blur->beginObject(passes::projectedBounds(s.scene.camera, s.frames[0].truth.pose, centre - glm::dvec3(0.035),
                                                centre + glm::dvec3(0.035), 0.01, 2),
                        blur_sigma_px, blur_smear_px);
    if (!compositor.drawSphereObject(s.scene.camera, s.frames[0].truth.pose, centre, 0.035, material, lighting, maps,
                                     error))
      return false;
    if (blur != nullptr && !blur->composite(blur_noise, blur_noise_texture, error)) return false;
    if (bloom == nullptr) return true;
    bloom->beginBrightPass(passes::projectedBounds(s.scene.camera, s.frames[0].truth.pose, centre - glm::dvec3(0.035),
                                                   centre + glm::dvec3(0.035), 0.01, 2));
    compositor.setBloomBrightPass(true);
    const bool drawn = compositor.drawSphereObject(s.scene.camera, s.frames[0].truth.pose, centre, 0.035, material,
                                                   lighting, maps, error);
    compositor.setBloomBrightPass(false);
    if (!drawn) {
      bloom->restore();
      return false;
    }
    return bloom->composite(error);
  }
};

// The sphere with its bloom (0.5 degrees of glare, camera_match.bloom's
// default): its cost over render/640x480 is the bright pass and the glare.
void renderFrameWithBloom(benchmark::State& state) {
  if (!requireGl(state)) return;
  RenderRig rig;
  std::string error;
  passes::ObjectBloom bloom;
  const CameraIntrinsics& camera = setup().scene.camera;
  if (!rig.init(error) || !bloom.init(camera.width_px, camera.height_px,
                                      camera.fx_px * std::tan(0.5 * M_PI / 180.0), ibl::CameraTransfer{}, error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  rig.bloom = &bloom;
  for (auto _ : state) {
    if (!rig.draw(error)) {
      state.SkipWithError(error.c_str());
      break;
    }
    glFinish();
  }
}

// With `match_noise`, the frame's noise added to the sphere (the compose
// stage with camera_match.noise); with `match_blur` too, the sphere through
// the blur layer by 1.04 px (a 1 px lens with the pixel's area) and the
// noise at its composite: their cost is the difference. With a smear
// (and no lens blur or noise), the sphere through the blur layer's box
// along it: the compose stage with camera_match.motion_blur, its
// Gaussian pass then one tap.
void renderFrame(benchmark::State& state, bool match_noise, bool match_blur = false,
                 const glm::dvec2& smear_px = glm::dvec2(0.0)) {
  if (!requireGl(state)) return;
  RenderRig rig;
  std::string error;
  if (!rig.init(error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  passes::SensorNoiseMatch match;
  match.model.dark_code = glm::dvec3(40.0);
  match.model.bright_code = glm::dvec3(190.0);
  match.model.dark_sigma_code = match.model.bright_sigma_code = glm::dvec3(1.5);
  passes::ObjectBlurLayer blur;
  passes::SensorNoiseTexture noise_texture;
  if (match_blur) {
    if (!blur.init(setup().scene.camera.width_px, setup().scene.camera.height_px, ibl::CameraTransfer{}, error) ||
        !noise_texture.init(error)) {
      state.SkipWithError(error.c_str());
      return;
    }
    rig.blur = &blur;
    rig.blur_sigma_px = 1.04;
    rig.blur_noise = &match;
    rig.blur_noise_texture = &noise_texture;
  } else if (smear_px != glm::dvec2(0.0)) {
    if (!blur.init(setup().scene.camera.width_px, setup().scene.camera.height_px, ibl::CameraTransfer{}, error)) {
      state.SkipWithError(error.c_str());
      return;
    }
    rig.blur = &blur;
    rig.blur_smear_px = smear_px;
  } else if (match_noise) {
    rig.compositor.setSensorNoise(&match);
  }
  for (auto _ : state) {
    ++match.frame_index;
    if (!rig.draw(error)) {
      state.SkipWithError(error.c_str());
      break;
    }
    glFinish();
  }
}

// The frame's noise measured on the tag's cells (ibl::measureSensorNoise,
// the match_noise stage's work), over the four frames at their true pose;
// the error is the added sigma's against the simulator's own (its
// noise_sigma_code), green, both inks, averaged over the frames.
void matchNoiseMeasure(benchmark::State& state) {
  Setup& s = setup();
  const std::optional<ibl::TagCellGrid> grid = tagCellGridOf(s.scene.rig);
  if (!grid) {
    state.SkipWithError("no tag grid");
    return;
  }
  auto measure = [&](const Frame& frame) {
    return ibl::measureSensorNoise(
        s.scene.camera, frame.truth.pose, *grid,
        [&frame](int x, int y) {
          const std::uint8_t* p = frame.rgb.row(y) + 3 * x;
          return glm::u8vec3(p[0], p[1], p[2]);
        },
        ibl::SensorNoiseSettings{});
  };
  const ErrorRow& row = errorsFor("match_noise/measure", [&] {
    double error_sum = 0.0;
    int measured = 0;
    for (const Frame& frame : s.frames) {
      const ibl::SensorNoiseReading reading = measure(frame);
      if (reading.status != ibl::SensorNoiseStatus::kMeasured) continue;
      const ibl::AddedNoiseModel model = ibl::addedNoiseModel(reading.dark, reading.bright);
      for (double sigma : {model.dark_sigma_code.y, model.bright_sigma_code.y})
        error_sum += std::abs(sigma - s.scene.noise_sigma_code) / s.scene.noise_sigma_code;
      ++measured;
    }
    ErrorRow out;
    out.values = {{"sigma_err_pct", measured > 0 ? 100.0 * error_sum / (2.0 * measured) : -1.0},
                  {"measured_pct", 100.0 * measured / static_cast<double>(s.frames.size())}};
    return out;
  });
  size_t next = 0;
  for (auto _ : state) {
    const ibl::SensorNoiseReading reading = measure(s.frames[next++ % s.frames.size()]);
    benchmark::DoNotOptimize(reading.bright.sigma_code);
  }
  setCounters(state, row);
}

void presentReadback(benchmark::State& state) {
  if (!requireGl(state)) return;
  RenderRig rig;
  std::string error;
  if (!rig.init(error) || !rig.draw(error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  glFinish();
  ImageRGB8 image;
  for (auto _ : state) {
    if (!rig.target.readRGB(image, error)) {
      state.SkipWithError(error.c_str());
      break;
    }
    benchmark::DoNotOptimize(image.pixels.data());
  }
}

void uploadFrame(benchmark::State& state) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  passes::CameraFrameTexture texture;
  std::string error;
  if (!texture.init(s.capabilities_full, error) || !texture.upload(s.frames[0].rgb, error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  size_t next = 0;
  for (auto _ : state) {
    if (!texture.upload(s.frames[next].rgb, error)) {
      state.SkipWithError(error.c_str());
      break;
    }
    glFinish();
    next = (next + 1) % s.frames.size();
  }
}

// The board camera's I420 frames: three planes uploaded and converted on
// the GPU (the path when dmabuf import is not available; llvmpipe has none).
void uploadI420Frame(benchmark::State& state) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  std::vector<FrameBuffer> frames(s.frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    const ImageRGB8& rgb = s.frames[i].rgb;
    encodeSimFrame(rgb, PixelLayout::kI420, frames[i]);
  }
  passes::CameraFrameTexture texture;
  std::string error;
  if (!texture.init(s.capabilities_full, error) || !texture.upload(frames[0], error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  size_t next = 0;
  for (auto _ : state) {
    if (!texture.upload(frames[next], error)) {
      state.SkipWithError(error.c_str());
      break;
    }
    glFinish();
    next = (next + 1) % frames.size();
  }
}

// The luma an RGB source computes for tag detection; a camera's Y' plane
// needs none of it.
void lumaFromRgbFrame(benchmark::State& state) {
  Setup& s = setup();
  std::vector<std::uint8_t> luma;
  size_t next = 0;
  for (auto _ : state) {
    lumaFromRgb(s.frames[next].rgb, luma);
    benchmark::DoNotOptimize(luma.data());
    next = (next + 1) % s.frames.size();
  }
}

// ---------------------------------------------------------------------------
// 5. CPU references

void cpuProbeToCube(benchmark::State& state, int face_size) {
  Setup& s = setup();
  ibl::ProbeToCubeParams params;
  params.face_size = face_size;
  params.probe_reflectance = s.scene.rig.probe_reflectance;
  for (auto _ : state) {
    ibl::CubeMapRGB map = ibl::probeImageToCubeMap(s.frames[0].view, s.frames[0].rgb, params);
    benchmark::DoNotOptimize(map.faces[0].data());
  }
  const std::string name = "cpu/probe_to_cube/face:" + std::to_string(face_size);
  const ErrorRow& row = errorsFor(name, [&] {
    ErrorRow r;
    const ibl::CubeMapRGB map = ibl::probeImageToCubeMap(s.frames[0].view, s.frames[0].rgb, params);
    // The CPU reference has no validity output: texels it cannot see are 0.
    std::vector<float> validity(static_cast<size_t>(ibl::kCubeFaceCount) * face_size * face_size, 1.0f);
    const ReflectionErrors e = compareReflection(map, validity, radianceTruth(face_size), s.frames[0].to_camera_w);
    r.values = {{"err100_pct", 100.0 * e.cone_main},
                {"err60_pct", 100.0 * e.cone_narrow},
                {"err100_sky_pct", 100.0 * e.sky}};
    return r;
  });
  setCounters(state, row);
}

// The multi-view probe's merge, per frame: the view's samples and their
// confidence (observeBall, with the validity the GPU pass reads back), the
// frame around the ball where the ball is blind (addFrameAroundBall), and
// the update of the accumulated probe (ProbeAccumulator::add), cycling
// through the frames. The reflection maps are made beforehand (their cost
// is probe_to_cube's row). Error: the 5 normals' irradiance of the merged
// probe against the clipped truth, beside frame 0's own map's.
void probeMerge(benchmark::State& state, bool use_frame) {
  Setup& s = setup();
  constexpr int kFace = 64;
  struct MergeInput {
    ibl::CubeMapRGB map{kFace};
    std::vector<float> validity;
  };
  static std::vector<MergeInput> inputs = [&] {
    std::vector<MergeInput> made;
    ibl::ProbeToCubeParams params;
    params.face_size = kFace;
    params.probe_reflectance = s.scene.rig.probe_reflectance;
    for (const Frame& frame : s.frames) {
      MergeInput input;
      input.map = ibl::probeImageToCubeMap(frame.view, frame.rgb, params);
      input.validity.assign(static_cast<std::size_t>(ibl::kCubeFaceCount) * kFace * kFace, 0.0f);
      for (int face = 0; face < ibl::kCubeFaceCount; ++face)
        for (int y = 0; y < kFace; ++y)
          for (int x = 0; x < kFace; ++x)
            if (ibl::reflectedDirectionToPixel(frame.view, ibl::cubeTexelCenterDirection(face, x, y, kFace), 1))
              input.validity[(static_cast<std::size_t>(face) * kFace + y) * kFace + x] = 1.0f;
      made.push_back(std::move(input));
    }
    return made;
  }();
  const ibl::HdrMergeSettings merge;
  const double clip_level = ibl::clippedMapLevel(merge, s.scene.rig.probe_reflectance);
  ibl::ProbeAccumulatorSettings settings;
  settings.noise.probe_reflectance = s.scene.rig.probe_reflectance;
  settings.noise.clip_level = clip_level;
  ibl::ObservationSettings observation_settings;
  observation_settings.use_frame = use_frame;
  RigGeometry rig = s.scene.rig;
  rig.post_radius_m = s.scene.post_radius_m;
  ibl::ProbeObservation observed(kFace);  // kept from frame to frame, as the kiosk would
  auto mergeFrame = [&](ibl::ProbeAccumulator& probe, std::size_t f) {
    const Frame& frame = s.frames[f];
    const ibl::LinearPixelReader read = [&](int x, int y, bool& clipped) {
      const std::uint8_t* p = frame.rgb.row(y) + 3 * x;
      clipped = std::max({p[0], p[1], p[2]}) >= merge.clip_code;
      // Camera linear: the map's units (the map divides the ball's reflectance out).
      return glm::dvec3(ibl::srgbToLinear(p[0] / 255.0), ibl::srgbToLinear(p[1] / 255.0), ibl::srgbToLinear(p[2] / 255.0));
    };
    ibl::observeBall(frame.view, inputs[f].map, &inputs[f].validity, nullptr, clip_level, observation_settings, observed);
    ibl::addFrameAroundBall(observed, frame.view, rig, read, observation_settings);
    return probe.add(observed);
  };
  const std::string name = std::string("probe_merge/") + (use_frame ? "ball+frame" : "ball") + "/face:64";
  const ErrorRow& row = errorsFor(name, [&] {
    ErrorRow r;
    ibl::ProbeAccumulator probe(settings);
    for (std::size_t f = 0; f < s.frames.size(); ++f) mergeFrame(probe, f);
    const ibl::CubeMapRGB merged = probe.radianceMap(static_cast<float>(clip_level));
    double merged_error = 0.0, single_error = 0.0;
    for (int i = 0; i < 5; ++i) {
      const double truth = s.irradiance_truth[i];
      merged_error += std::abs(luminance(ibl::irradianceFromCubeMap(merged, kNormals[i])) - truth) / truth / 5.0;
      single_error += std::abs(luminance(ibl::irradianceFromCubeMap(inputs[0].map, kNormals[i])) - truth) / truth / 5.0;
    }
    r.values = {{"merged_err_pct", 100.0 * merged_error},
                {"frame0_err_pct", 100.0 * single_error},
                {"seen_pct", 100.0 * probe.seenSolidAngleFraction()}};
    return r;
  });
  ibl::ProbeAccumulator probe(settings);
  std::size_t next = 0;
  for (auto _ : state) {
    const ibl::AccumulateCounts counts = mergeFrame(probe, next);
    benchmark::DoNotOptimize(counts.seen);
    next = (next + 1) % s.frames.size();
  }
  setCounters(state, row);
}

void cpuBlurPass(benchmark::State& state, int input_face_size, int output_face_size, int half_taps) {
  ibl::SphericalBlurPass pass;
  pass.axis = ibl::BlurAxis::kEast;
  pass.half_taps = half_taps;
  const ibl::CubeMapRGB& input = cpuReflection(input_face_size, 4);
  for (auto _ : state) {
    ibl::CubeMapRGB output = ibl::sphericalBlurPass(input, output_face_size, pass);
    benchmark::DoNotOptimize(output.faces[0].data());
  }
}

// ---------------------------------------------------------------------------
// 5. Each stage against its limit (stage_limits.hpp), at the shipped
//    defaults, stage then limit back to back in one run: per-iteration
//    times, glFinish included, whose medians make the ratio.

std::map<std::string, std::vector<double>>& ratioSamples() {
  static std::map<std::string, std::vector<double>> samples;
  return samples;
}

// Runs `body` once per iteration, timing each (its glFinish included).
template <typename Body>
void timeIterations(benchmark::State& state, const std::string& key, Body body) {
  std::vector<double>& samples = ratioSamples()[key];
  std::string error;
  // Once untimed: llvmpipe compiles a shader at its first draw.
  if (!body(error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    if (!body(error)) {
      state.SkipWithError(error.c_str());
      break;
    }
    samples.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
}

std::string ratioKey(const std::string& stage, bool limit) { return stage + (limit ? "/limit" : ""); }

// A still camera: frames of the simulator's static path, each with its own
// sensor noise, for the tracker's still case.
const std::vector<Frame>& stillFrames() {
  static const std::vector<Frame> frames = [] {
    Setup& s = setup();
    sim::SceneConfig scene = s.scene;
    scene.camera_path.name = "static";
    sim::World world(scene);
    std::vector<Frame> out;
    for (std::uint64_t index = 0; index < 10; ++index) {
      Frame frame;
      frame.index = index;
      world.render(index, frame.rgb, frame.truth);
      lumaFromRgb(frame.rgb, frame.luma);
      out.push_back(std::move(frame));
    }
    return out;
  }();
  return frames;
}

// detect_pose's limit: the detector and the planar pose alone (no corner
// refinement, no polish), on the same frames in the same order.
void ratioDetectPose(benchmark::State& state, bool still, bool limit) {
  Setup& s = setup();
  const std::vector<Frame>& frames = still ? stillFrames() : s.consecutive_frames;
  tracking::TagDetectorSettings settings;
  settings.family = s.scene.rig.tag_family;
  settings.refine_corners = !limit;
  tracking::TagTracker tracker(settings, s.scene.rig, s.scene.camera);
  std::size_t next = 0;
  timeIterations(state, ratioKey(still ? "detect_pose (still)" : "detect_pose (moving)", limit), [&](std::string& error) {
    if (next == 0) tracker.resetHistory();
    const Frame& frame = frames[next];
    const tracking::TagTrackResult result = tracker.track(frame.luma.data(), frame.rgb.width, frame.rgb.height, frame.rgb.width);
    next = (next + 1) % frames.size();
    if (!result.found) error = "tag not found: " + result.status;
    return result.found;
  });
}

// upload's limit: glTexSubImage2D of the same bytes into a texture of the same size.
void ratioUpload(benchmark::State& state, bool limit) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  passes::CameraFrameTexture texture;
  std::string error;
  const ImageRGB8& image = s.frames[0].rgb;
  if (!texture.init(s.capabilities_full, error) || !texture.upload(image, error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  timeIterations(state, ratioKey("upload", limit), [&](std::string& e) {
    if (limit) {
      glBindTexture(GL_TEXTURE_2D, texture.texture());
      glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, image.width, image.height, GL_RGB, GL_UNSIGNED_BYTE, image.pixels.data());
      glBindTexture(GL_TEXTURE_2D, 0);
    } else if (!texture.upload(image, e)) {
      return false;
    }
    glFinish();
    return true;
  });
}

void ratioProbeToCube(benchmark::State& state, bool limit) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  std::string error;
  FrameTextures frames;
  passes::EnvironmentMaps maps;
  {
    TrivialShaderScope trivial(limit);
    if (!frames.init(s.capabilities_full, error) || !maps.init(s.capabilities_full, {}, error)) {
      state.SkipWithError(error.c_str());
      return;
    }
  }
  timeIterations(state, ratioKey("probe_to_cube", limit), [&](std::string& e) {
    const bool ok = maps.updateReflection(*frames.textures[0], s.frames[0].view, s.scene.rig.probe_reflectance, e);
    glFinish();
    return ok;
  });
}

void ratioDiffuse(benchmark::State& state, bool limit) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  std::string error;
  FrameTextures frames;
  passes::EnvironmentMaps maps;
  {
    TrivialShaderScope trivial(limit, "cosine_irradiance.frag");
    if (!frames.init(s.capabilities_full, error) || !maps.init(s.capabilities_full, {}, error) ||
        !maps.updateReflection(*frames.textures[0], s.frames[0].view, s.scene.rig.probe_reflectance, error)) {
      state.SkipWithError(error.c_str());
      return;
    }
  }
  glFinish();
  timeIterations(state, ratioKey("diffuse_blur", limit), [&](std::string& e) {
    const bool ok = maps.updateDiffuse(e);
    glFinish();
    return ok;
  });
}

// The frame as the kiosk draws it: the background, the shadow's cells and
// the sphere (render), and the ground shadow's update on its own (shadows).
void ratioRender(benchmark::State& state, bool limit) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  std::string error;
  RenderRig rig;
  ShadowRig shadow_rig;
  passes::GroundShadow shadow;
  if (!rig.init(error) || !shadow_rig.init(error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  const std::vector<ibl::ShadowLight> lights =
      ibl::groundShadowLights(ibl::fitLightDome(*shadow_rig.reflection, &shadow_rig.validity));
  passes::ObjectCompositor compositor;
  {
    // The shadow's own passes stay real (its cells are the real ones); the
    // frame's three draws get the trivial shaders.
    TrivialShaderScope trivial_composite(limit, "ground_composite.frag");
    if (!shadow.init(s.capabilities_full, {}, error) || !shadow.update(lights, benchCaster(), error)) {
      state.SkipWithError(error.c_str());
      return;
    }
  }
  {
    TrivialShaderScope trivial(limit);
    if (!compositor.init(s.capabilities_full, {}, rig.maps.storage(), error)) {
      state.SkipWithError(error.c_str());
      return;
    }
  }
  ibl::SurfaceMaterial material;
  material.albedo = glm::vec3(0.8f);
  material.k_specular = 0.25f;
  material.shininess = 48.0f;
  material.k_reflect = 0.08f;
  const PoseCamFromWorld& pose = s.frames[0].truth.pose;
  const ibl::ShadowCaster caster = benchCaster();
  timeIterations(state, ratioKey("render", limit), [&](std::string& e) {
    rig.target.bind();
    compositor.drawCameraBackground(*rig.frames.textures[0]);
    const bool ok = shadow.drawOnCameraImage(s.scene.camera, pose, *rig.frames.textures[0], e) &&
                    compositor.drawSphereObject(s.scene.camera, pose,
                                                glm::dvec3(caster.position_w, caster.radius_m), caster.radius_m,
                                                material, ibl::SceneLighting{}, rig.maps, e);
    glFinish();
    return ok;
  });
}

void ratioShadows(benchmark::State& state, bool limit) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  std::string error;
  ShadowRig rig;
  if (!rig.init(error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  const std::vector<ibl::ShadowLight> lights = ibl::groundShadowLights(ibl::fitLightDome(*rig.reflection, &rig.validity));
  passes::GroundShadow shadow;
  {
    TrivialShaderScope trivial(limit);
    if (!shadow.init(s.capabilities_full, {}, error)) {
      state.SkipWithError(error.c_str());
      return;
    }
  }
  timeIterations(state, ratioKey("shadows", limit), [&](std::string& e) {
    const bool ok = shadow.update(lights, benchCaster(), e);
    glFinish();
    return ok;
  });
}

double medianOf(std::vector<double> values) {
  if (values.empty()) return NAN;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

void printRatioTable() {
  if (ratioSamples().empty()) return;
  std::printf("\nEach stage against its limit (the same passes with trivial shaders of as many texture reads;\n"
              "detect_pose: the detector and the planar pose without refinement; upload: glTexSubImage2D alone).\n"
              "Medians of per-iteration times, glFinish included, stage and limit back to back in this run:\n");
  std::printf("  %-22s %10s %10s %8s\n", "stage", "ms", "limit ms", "ratio");
  for (const char* stage : {"upload", "detect_pose (still)", "detect_pose (moving)", "probe_to_cube", "diffuse_blur",
                            "render", "shadows"}) {
    const auto own = ratioSamples().find(stage), limit = ratioSamples().find(std::string(stage) + "/limit");
    if (own == ratioSamples().end() || limit == ratioSamples().end()) continue;
    const double ms = medianOf(own->second), limit_ms = medianOf(limit->second);
    std::printf("  %-22s %10.2f %10.2f %7.2fx\n", stage, ms, limit_ms, ms / limit_ms);
  }
}

void printErrorTable() {
  if (errorTable().empty()) return;
  std::printf("\nError against the simulator's truth (per configuration; deterministic, so not repeated):\n");
  for (const auto& [name, row] : errorTable()) {
    std::printf("  %-56s", name.c_str());
    for (const auto& [key, value] : row.values) std::printf("  %s=%.3f", key.c_str(), value);
    std::printf("\n");
  }
  std::printf(
      "  err100/err60: relative luminance error sum|map - truth| / sum(truth) of the reflection map within 100/60 deg\n"
      "  of the direction back to the camera (behind that the ball shows directions only in its rim, and straight\n"
      "  behind it not at all: the blind spot); err100_sky: the same above the horizon only (the ground is near, so\n"
      "  the ball sees it with parallax that the centre-based truth does not have); err_valid: every texel the\n"
      "  stage marked valid. GPU rows: mean over the frames; cpu/probe_to_cube: frame 0 only.\n"
      "  Diffuse: mean over up and 4 horizontal normals of |pi*diffuse - E|/E, E being the sim's clipped irradiance\n"
      "  (err_vs_truth) or its unclipped one (err_vs_hdr: what an 8-bit camera cannot see), irradianceFromCubeMap\n"
      "  of the read-back reflection map (blur_err: the blur's own error), and that reference against the clipped\n"
      "  truth (probe_part: what the reflection map costs the irradiance).\n");
}

void registerAll() {
  using benchmark::kMillisecond;
  constexpr double kMinTime = 0.2;

  for (DetectMode mode : {DetectMode::kAcquire, DetectMode::kTrack})
    for (int decimate : {1, 2, 3})
      for (int threads : {1, 2}) {
        // More threads than libapriltag survives is no benchmark (maxDetectorThreads).
        if (threads > tracking::maxDetectorThreads()) continue;
        benchmark::RegisterBenchmark((std::string("detect_pose/") + (mode == DetectMode::kTrack ? "track" : "acquire") +
                                      "/decimate:" + std::to_string(decimate) + "/threads:" + std::to_string(threads))
                                         .c_str(),
                                     [=](benchmark::State& state) { detectPose(state, decimate, threads, mode); })
            ->Unit(kMillisecond)
            ->UseRealTime()
            ->MinTime(kMinTime);
      }

  benchmark::RegisterBenchmark("upload/640x480", uploadFrame)->Unit(kMillisecond)->UseRealTime()->MinTime(kMinTime);
  benchmark::RegisterBenchmark("upload/640x480/i420", uploadI420Frame)
      ->Unit(kMillisecond)->UseRealTime()->MinTime(kMinTime);
  benchmark::RegisterBenchmark("luma_from_rgb/640x480", lumaFromRgbFrame)
      ->Unit(kMillisecond)->UseRealTime()->MinTime(kMinTime);

  for (bool eight_bit : {false, true})
    for (int face : {32, 64, 128})
      for (int iterations : {1, 2, 4})
        benchmark::RegisterBenchmark((std::string("probe_to_cube/") + (eight_bit ? "8bit" : "half") + "/face:" +
                                      std::to_string(face) + "/iters:" + std::to_string(iterations))
                                         .c_str(),
                                     [=](benchmark::State& state) { probeToCube(state, eight_bit, face, iterations); })
            ->Unit(kMillisecond)
            ->UseRealTime()
            ->MinTime(kMinTime);

  // The sweep: rows of the latitude-longitude maps (the north pass's taps) by
  // the east pass's taps.
  for (int rows : {16, 32, 64})
    for (int taps : {4, 8, 16}) {
      if (rows == passes::EnvironmentMapSettings{}.intermediate_rows && taps == 16) continue;  // the default, below
      benchmark::RegisterBenchmark(diffuseName(false, rows, 16, taps, false).c_str(),
                                   [=](benchmark::State& state) { diffuseBlur(state, false, rows, 16, taps); })
          ->Unit(kMillisecond)
          ->UseRealTime()
          ->MinTime(kMinTime);
    }
  // The 8-bit path at a 32² diffuse map and 8 half-taps (kept for comparison with earlier runs).
  benchmark::RegisterBenchmark(diffuseName(true, 32, 32, 8, false).c_str(),
                               [](benchmark::State& state) { diffuseBlur(state, true, 32, 32, 8); })
      ->Unit(kMillisecond)
      ->UseRealTime()
      ->MinTime(kMinTime);
  // The app's own default (passes::EnvironmentMapSettings: 32 rows,
  // diffuse 16, 16 half-taps), half float and 8-bit.
  {
    const passes::EnvironmentMapSettings defaults;
    const int intermediate = defaults.intermediate_rows, face = defaults.diffuse_face_size,
              taps = defaults.blur_half_taps;
    for (bool eight_bit : {false, true})
      benchmark::RegisterBenchmark(diffuseName(eight_bit, intermediate, face, taps, false).c_str(),
                                   [=](benchmark::State& state) {
                                     diffuseBlur(state, eight_bit, intermediate, face, taps);
                                   })
          ->Unit(kMillisecond)
          ->UseRealTime()
          ->MinTime(kMinTime);
  }

  for (bool eight_bit : {false, true})
    benchmark::RegisterBenchmark(diffuseName(eight_bit, 16, 16, 0, true).c_str(),
                                 [=](benchmark::State& state) { diffuseBlur(state, eight_bit, 16, 16, 0, true); })
        ->Unit(kMillisecond)
        ->UseRealTime()
        ->MinTime(kMinTime);

  for (ibl::DomePlacement placement :
       {ibl::DomePlacement::kFixedRegions, ibl::DomePlacement::kMedianCut, ibl::DomePlacement::kClustered})
    benchmark::RegisterBenchmark((std::string("fit_lights/") + ibl::toString(placement) + "/lights:8").c_str(),
                                 [=](benchmark::State& state) { fitLights(state, placement, 8); })
        ->Unit(kMillisecond)
        ->UseRealTime()
        ->MinTime(kMinTime);
  for (int count : {4, 8, 16})
    benchmark::RegisterBenchmark(("shadows/clustered/lights:" + std::to_string(count)).c_str(),
                                 [=](benchmark::State& state) { shadows(state, ibl::DomePlacement::kClustered, count); })
        ->Unit(kMillisecond)
        ->UseRealTime()
        ->MinTime(kMinTime);
  for (ibl::DomePlacement placement : {ibl::DomePlacement::kFixedRegions, ibl::DomePlacement::kMedianCut})
    benchmark::RegisterBenchmark((std::string("shadows/") + ibl::toString(placement) + "/lights:8").c_str(),
                                 [=](benchmark::State& state) { shadows(state, placement, 8); })
        ->Unit(kMillisecond)
        ->UseRealTime()
        ->MinTime(kMinTime);
  benchmark::RegisterBenchmark("shadow_composite/640x480", shadowComposite)->Unit(kMillisecond)->UseRealTime()->MinTime(kMinTime);
  benchmark::RegisterBenchmark("virtual_lamp/640x480", [](benchmark::State& state) { virtualLampComposite(state, false); })
      ->Unit(kMillisecond)
      ->UseRealTime()
      ->MinTime(kMinTime);
  benchmark::RegisterBenchmark("virtual_lamp/640x480/whole_frame_pass",
                               [](benchmark::State& state) { virtualLampComposite(state, true); })
      ->Unit(kMillisecond)
      ->UseRealTime()
      ->MinTime(kMinTime);
  benchmark::RegisterBenchmark("render/640x480", [](benchmark::State& state) { renderFrame(state, false); })
      ->Unit(kMillisecond)
      ->UseRealTime()
      ->MinTime(kMinTime);
  benchmark::RegisterBenchmark("render/640x480/match_noise_blur",
                               [](benchmark::State& state) { renderFrame(state, true, true); })
      ->Unit(kMillisecond)
      ->UseRealTime()
      ->MinTime(kMinTime);
  benchmark::RegisterBenchmark("render/640x480/match_noise", [](benchmark::State& state) { renderFrame(state, true); })
      ->Unit(kMillisecond)
      ->UseRealTime()
      ->MinTime(kMinTime);
  // The pan path's fastest smear over 10 ms (sim camera_path pan): 7 px.
  benchmark::RegisterBenchmark("render/640x480/motion_blur",
                               [](benchmark::State& state) { renderFrame(state, false, false, glm::dvec2(7.0, 0.0)); })
      ->Unit(kMillisecond)
      ->UseRealTime()
      ->MinTime(kMinTime);
  benchmark::RegisterBenchmark("render/640x480/bloom", renderFrameWithBloom)
      ->Unit(kMillisecond)
      ->UseRealTime()
      ->MinTime(kMinTime);
  benchmark::RegisterBenchmark("match_noise/measure", matchNoiseMeasure)->Unit(kMillisecond)->MinTime(kMinTime);
  benchmark::RegisterBenchmark("present_readback/640x480", presentReadback)
      ->Unit(kMillisecond)
      ->UseRealTime()
      ->MinTime(kMinTime);

  // Stage, then its limit, for each stage (printRatioTable).
  const std::pair<const char*, std::function<void(benchmark::State&, bool)>> ratio_stages[] = {
      {"upload", ratioUpload},
      {"detect_pose/still", [](benchmark::State& state, bool limit) { ratioDetectPose(state, true, limit); }},
      {"detect_pose/moving", [](benchmark::State& state, bool limit) { ratioDetectPose(state, false, limit); }},
      {"probe_to_cube", ratioProbeToCube},
      {"diffuse_blur", ratioDiffuse},
      {"render", ratioRender},
      {"shadows", ratioShadows}};
  for (const auto& [stage, run] : ratio_stages)
    for (bool limit : {false, true})
      benchmark::RegisterBenchmark((std::string("ratio/") + stage + (limit ? "/limit" : "")).c_str(),
                                   [run = run, limit](benchmark::State& state) { run(state, limit); })
          ->Unit(kMillisecond)
          ->UseRealTime()
          ->MinTime(0.5);

  benchmark::RegisterBenchmark("cpu/probe_to_cube/face:64", [](benchmark::State& state) { cpuProbeToCube(state, 64); })
      ->Unit(kMillisecond)
      ->MinTime(kMinTime);
  for (bool use_frame : {false, true})
    benchmark::RegisterBenchmark((std::string("probe_merge/") + (use_frame ? "ball+frame" : "ball") + "/face:64").c_str(),
                                 [=](benchmark::State& state) { probeMerge(state, use_frame); })
        ->Unit(kMillisecond)
        ->UseRealTime()
        ->MinTime(kMinTime);
  for (bool eight_bit : {false, true})
    benchmark::RegisterBenchmark((std::string("probe_merge/kiosk/") + (eight_bit ? "8bit" : "half") + "/face:64").c_str(),
                                 [=](benchmark::State& state) { probeMergeKiosk(state, eight_bit); })
        ->Unit(kMillisecond)
        ->UseRealTime()
        ->MinTime(kMinTime);
  benchmark::RegisterBenchmark("cpu/blur_pass/64to32/half_taps:8",
                               [](benchmark::State& state) { cpuBlurPass(state, 64, 32, 8); })
      ->Unit(kMillisecond)
      ->MinTime(kMinTime);
}

}  // namespace
}  // namespace probelight::bench

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  probelight::bench::registerAll();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  std::fflush(stdout);
  probelight::bench::printErrorTable();
  probelight::bench::printRatioTable();
  return 0;
}
