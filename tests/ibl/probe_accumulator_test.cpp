// ibl/probe_accumulator and ibl/probe_observation: the probe gathered over
// views, against radiance this file knows exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "ibl/camera_projection.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/probe_accumulator.hpp"
#include "ibl/probe_observation.hpp"
#include "ibl_test_helpers.hpp"

namespace probelight::ibl {
namespace {

constexpr int kAccumulatorFace = 32;

double lum(const glm::vec3& rgb) { return luminance(glm::dvec3(rgb)); }

// A sky brighter toward the zenith, a darker ground, and a lamp of
// `lamp_level` within 12 deg of `lamp_w` (0: off).
glm::vec3 room(const glm::dvec3& d, double lamp_level = 0.0, const glm::dvec3& lamp_w = {0.6, 0.0, 0.8}) {
  glm::dvec3 value = d.z > 0.0 ? glm::dvec3(0.3, 0.35, 0.45) * (0.6 + 0.4 * d.z) : glm::dvec3(0.15, 0.13, 0.1);
  if (lamp_level > 0.0 && glm::dot(d, glm::normalize(lamp_w)) > std::cos(glm::radians(12.0)))
    value = glm::dvec3(lamp_level);
  return glm::vec3(value);
}

ProbeAccumulatorSettings settingsForTests() {
  ProbeAccumulatorSettings settings;
  settings.face_size = kAccumulatorFace;
  settings.noise.clip_level = 1.0;
  return settings;
}

// Every texel seen with `confidence`, the room plus Gaussian noise of the
// accumulator's own model (so the test measures the rule, not the model).
ProbeObservation noisyView(std::mt19937& rng, float confidence, double lamp_level = 0.0, bool clip = false) {
  const NoiseLookup noise(settingsForTests().noise);
  ProbeObservation view(kAccumulatorFace);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const std::size_t per_face = static_cast<std::size_t>(kAccumulatorFace) * kAccumulatorFace;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < kAccumulatorFace; ++y)
      for (int x = 0; x < kAccumulatorFace; ++x) {
        const std::size_t local = static_cast<std::size_t>(y) * kAccumulatorFace + x;
        glm::vec3 value = room(cubeTexelCenterDirection(face, x, y, kAccumulatorFace), lamp_level);
        value *= static_cast<float>(1.0 + gauss(rng) * noise.sigma(lum(value)) / std::max(lum(value), 1e-9));
        bool bound = false;
        if (clip && lum(value) > 1.0) {
          value = glm::vec3(1.0f);
          bound = true;
        }
        view.radiance.faces[face][local] = value;
        view.confidence[face * per_face + local] = confidence;
        view.lower_bound[face * per_face + local] = bound;
      }
  return view;
}

double meanRelativeError(const ProbeAccumulator& probe, double lamp_level = 0.0) {
  double sum = 0.0;
  long count = 0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < kAccumulatorFace; ++y)
      for (int x = 0; x < kAccumulatorFace; ++x) {
        const std::size_t i = (static_cast<std::size_t>(face) * kAccumulatorFace + y) * kAccumulatorFace + x;
        const double truth = lum(room(cubeTexelCenterDirection(face, x, y, kAccumulatorFace), lamp_level));
        sum += std::abs(lum(probe.radiance(i)) - truth) / truth;
        ++count;
      }
  return sum / count;
}

TEST(ProbeAccumulator, ASteadyRoomConvergesWithoutFalseChanges) {
  std::mt19937 rng(7);
  ProbeAccumulator probe(settingsForTests());
  AccumulateCounts first = probe.add(noisyView(rng, 100.0f));
  EXPECT_EQ(first.first, 6L * kAccumulatorFace * kAccumulatorFace);
  const double single = meanRelativeError(probe);
  long changed = 0;
  for (int view = 1; view < 20; ++view) changed += probe.add(noisyView(rng, 100.0f)).changed;
  const double after = meanRelativeError(probe);
  // 20 equal views of independent noise: the error of their mean is
  // 1/sqrt(20) of one's (0.22); the decay (memory 30 views) costs little.
  EXPECT_LT(after, 0.3 * single) << single << " -> " << after;
  // 3 sigma outside the range of a 3x3 neighbourhood: a false alarm needs
  // a 3-sigma outlier beyond 9 samples' extremes. Far under 1 in 1000.
  EXPECT_LT(changed, 19L * 6 * kAccumulatorFace * kAccumulatorFace / 1000) << changed;
}

TEST(ProbeAccumulator, ALampSwitchedOnShowsWholeInOneView) {
  std::mt19937 rng(11);
  ProbeAccumulator probe(settingsForTests());
  for (int view = 0; view < 10; ++view) probe.add(noisyView(rng, 1000.0f));
  // The next view has the lamp on, and is less sure of its directions
  // (sigma 2.9 deg, a texel: a view of it toward the ball's rim) than the
  // views before: it still shows the whole lamp, whose core (wider than
  // the sigma) no misplaced direction explains.
  const AccumulateCounts counts = probe.add(noisyView(rng, 400.0f, /*lamp_level=*/30.0));
  EXPECT_GT(counts.changed, 0);
  long lamp_texels = 0, lamp_right = 0, others_moved = 0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < kAccumulatorFace; ++y)
      for (int x = 0; x < kAccumulatorFace; ++x) {
        const std::size_t i = (static_cast<std::size_t>(face) * kAccumulatorFace + y) * kAccumulatorFace + x;
        const glm::dvec3 d = cubeTexelCenterDirection(face, x, y, kAccumulatorFace);
        const double truth = lum(room(d, 30.0));
        const double got = lum(probe.radiance(i));
        if (truth == 30.0) {
          ++lamp_texels;
          // The noise model's sigma at 30 (above the clip, relative) is
          // ~2.5%: 4 sigma.
          if (std::abs(got - truth) < 0.1 * truth) ++lamp_right;
        } else if (std::abs(got - truth) > 0.2 * truth) {
          ++others_moved;
        }
      }
  ASSERT_GT(lamp_texels, 30);
  EXPECT_EQ(lamp_right, lamp_texels) << "the lamp, edges included, is there after one view";
  EXPECT_EQ(others_moved, 0);
  // And off again: back within one view.
  probe.add(noisyView(rng, 400.0f));
  EXPECT_LT(meanRelativeError(probe), 0.02);
}

TEST(ProbeAccumulator, ASurerViewOutweighsALessSureOne) {
  ProbeAccumulator probe(settingsForTests());
  ProbeObservation good(kAccumulatorFace), rim(kAccumulatorFace);
  // One texel, its values within noise of each other (1% apart at 0.5).
  good.radiance.faces[0][0] = glm::vec3(0.5f);
  good.confidence[0] = 1000.0f;
  rim.radiance.faces[0][0] = glm::vec3(0.505f);
  rim.confidence[0] = 10.0f;
  probe.add(good);
  const AccumulateCounts counts = probe.add(rim);
  EXPECT_EQ(counts.merged, 1);
  // Weighted 1000 * 0.5 * (1 - 1/30) against 10 * 0.505.
  const double decayed = 1000.0 * (1.0 - 1.0 / 30.0);
  EXPECT_NEAR(probe.radiance(0).x, (decayed * 0.5 + 10.0 * 0.505) / (decayed + 10.0), 1e-6);
  EXPECT_NEAR(probe.confidence(0), decayed + 10.0, 1e-2);
  // A texel only one of them saw: the other leaves it alone.
  ProbeObservation elsewhere(kAccumulatorFace);
  elsewhere.radiance.faces[1][5] = glm::vec3(0.2f);
  elsewhere.confidence[static_cast<std::size_t>(kAccumulatorFace) * kAccumulatorFace + 5] = 1.0f;
  probe.add(elsewhere);
  EXPECT_NEAR(probe.radiance(0).x, (decayed * 0.5 + 10.0 * 0.505) / (decayed + 10.0), 1e-6);
  EXPECT_EQ(probe.seenTexels(), 2);
  EXPECT_EQ(probe.validity()[0], 1.0f);
  EXPECT_EQ(probe.validity()[1], 0.0f);
}

TEST(ProbeAccumulator, AClippedSampleIsALowerBound) {
  ProbeAccumulator probe(settingsForTests());
  auto one = [](float value, bool bound, float confidence = 100.0f) {
    ProbeObservation view(kAccumulatorFace);
    for (int t = 0; t < 9; ++t) {  // a 3x3 patch, so that neighbourhoods agree
      const std::size_t i = static_cast<std::size_t>(t / 3) * kAccumulatorFace + t % 3;
      view.radiance.faces[0][i] = glm::vec3(value);
      view.confidence[i] = confidence;
      view.lower_bound[i] = bound;
    }
    return view;
  };
  // A bracket measured the sun at 50.
  probe.add(one(50.0f, false));
  // Live frames clip at 1: consistent, the 50 stays.
  AccumulateCounts counts = probe.add(one(1.0f, true));
  EXPECT_EQ(counts.kept, 9);
  EXPECT_FLOAT_EQ(probe.radiance(0).x, 50.0f);
  EXPECT_FALSE(probe.lowerBound(0));
  // A cloud: an unclipped 0.8 is below 50 beyond noise: the light changed.
  counts = probe.add(one(0.8f, false));
  EXPECT_EQ(counts.changed, 9);
  EXPECT_NEAR(probe.radiance(0).x, 0.8f, 1e-6);
  // The sun back, clipping: raised to the bound, flagged.
  counts = probe.add(one(1.0f, true));
  EXPECT_EQ(counts.changed, 9);
  EXPECT_TRUE(probe.lowerBound(0));
  EXPECT_EQ(probe.lowerBounds()[0], 1);
  // A measurement above the bound replaces it.
  counts = probe.add(one(3.0f, false));
  EXPECT_FALSE(probe.lowerBound(0));
  EXPECT_NEAR(probe.radiance(0).x, 3.0f, 1e-6);
  // A darker measurement than a bound breaks it.
  probe.add(one(1.0f, true));
  probe.add(one(1.2f, true));  // two bounds: the higher holds
  EXPECT_NEAR(probe.radiance(0).x, 3.0f, 1e-6);
}

TEST(ProbeAccumulator, BadObservationsChangeNothing) {
  ProbeAccumulator probe(settingsForTests());
  EXPECT_THROW(probe.add(ProbeObservation(kAccumulatorFace * 2)), std::invalid_argument);
  ProbeObservation view(kAccumulatorFace);
  view.radiance.faces[0][0] = glm::vec3(NAN, 0.0f, 0.0f);
  view.confidence[0] = 100.0f;
  view.radiance.faces[0][1] = glm::vec3(INFINITY);
  view.confidence[1] = 100.0f;
  EXPECT_EQ(probe.add(view).seen, 0);
  EXPECT_TRUE(probe.empty());
  std::string error;
  std::vector<glm::vec4> texels = probe.texels();
  texels[3] = glm::vec4(NAN);
  EXPECT_FALSE(probe.restore(texels, error));
  EXPECT_NE(error.find("texel 3"), std::string::npos) << error;
  EXPECT_FALSE(probe.restore(std::vector<glm::vec4>(5), error));
  texels[3] = glm::vec4(0.5f, 0.5f, 0.5f, -2.0f);
  ASSERT_TRUE(probe.restore(texels, error)) << error;
  EXPECT_TRUE(probe.lowerBound(3));
  EXPECT_EQ(probe.seenTexels(), 1);
  probe.scaleRadiance(2.0);
  EXPECT_FLOAT_EQ(probe.radiance(3).x, 1.0f);
  probe.scaleRadiance(NAN);
  EXPECT_FLOAT_EQ(probe.radiance(3).x, 1.0f);
}

TEST(ProbeAccumulator, TheNoiseModelIsOneCodeStepTimesTheCodeSigma) {
  SampleNoise model;
  model.code_sigma = 2.0;
  model.probe_reflectance = 0.5;
  model.clip_level = 2.0;  // 1 / reflectance
  const NoiseLookup noise(model);
  // At code 128 the sRGB step is about 0.0038 linear; over the reflectance 0.0076.
  const double at_128 = srgbToLinear(128.0 / 255.0) / 0.5;
  const double step = (srgbToLinear(128.5 / 255.0) - srgbToLinear(127.5 / 255.0)) / 0.5;
  EXPECT_NEAR(noise.sigma(at_128), 2.0 * step, 0.1 * 2.0 * step);
  // Above the clip, the clip's relative noise.
  EXPECT_NEAR(noise.sigma(20.0) / 20.0, noise.sigma(2.0) / 2.0, 1e-12);
}

// A kiosk-like view of a 3 cm ball 0.5 m away.
MirrorBallView kioskView(const glm::dvec3& eye_w) {
  MirrorBallView view;
  view.camera.width_px = 640;
  view.camera.height_px = 480;
  view.camera.fx_px = view.camera.fy_px = 600.0;
  view.camera.cx_px = 319.5;
  view.camera.cy_px = 239.5;
  view.center_w = {0.12, 0.0, 0.08};
  view.radius_m = 0.03;
  view.pose = testing::poseSeeingPointAtPixel(view.camera, eye_w, view.center_w, {330.0, 250.0});
  return view;
}

TEST(ProbeObservation, ConfidenceFallsTowardTheRimAndGrowsWithTheBall) {
  const glm::dvec3 eye{0.12, -0.5, 0.35};
  const MirrorBallView view = kioskView(eye);
  const glm::dvec3 v = glm::normalize(eye - view.center_w);
  const ObservationSettings settings;
  const double texel = 0.5 * M_PI / 64;
  // Straight back toward the eye: normal incidence.
  const double centre = ballSampleConfidence(view, v, texel, settings);
  // The pixel footprint and pose error over (R/2)^2 px^2/rad^2, plus the texel's size.
  const double radius_px = 600.0 * 0.03 / std::sqrt(glm::dot(eye - view.center_w, eye - view.center_w) - 0.03 * 0.03);
  const double expected = 1.0 / ((1.0 / 12.0 + 0.0625) * std::pow(2.0 / radius_px, 2) + texel * texel / 12.0);
  EXPECT_NEAR(centre, expected, 1e-6 * expected);
  double previous = centre;
  // Turning the reflected direction away from the eye: incidence grows.
  const glm::dvec3 side = glm::normalize(glm::cross(v, glm::dvec3(0, 0, 1)));
  for (double alpha_deg = 20.0; alpha_deg < 180.0; alpha_deg += 20.0) {
    const double a = glm::radians(alpha_deg);
    const double c = ballSampleConfidence(view, std::cos(a) * v + std::sin(a) * side, texel, settings);
    EXPECT_LT(c, previous) << alpha_deg;
    previous = c;
  }
  // Straight behind: nothing.
  EXPECT_EQ(ballSampleConfidence(view, -v, texel, settings), 0.0);
  // Twice as near: about four times the confidence (the footprint term).
  const MirrorBallView near = kioskView(view.center_w + 0.5 * (eye - view.center_w));
  const double near_centre = ballSampleConfidence(near, v, texel, settings);
  EXPECT_GT(near_centre / centre, 3.0);
  EXPECT_LT(near_centre / centre, 4.2);
}

// A world the frame shows: sky by direction, the ground plane by position.
glm::dvec3 skyRadiance(const glm::dvec3& d) { return glm::dvec3(0.2 + 0.5 * std::max(0.0, d.z), 0.3, 0.5 - 0.2 * d.x); }
glm::dvec3 groundRadiance(const glm::dvec3& p) { return glm::dvec3(0.1 + 0.05 * std::sin(8.0 * p.x), 0.12, 0.08 + 0.04 * std::cos(6.0 * p.y)); }

TEST(ProbeObservation, TheFrameAroundTheBallFillsItsBlindSpotWithTheRightLight) {
  // Below the ball: straight behind it is sky, which the frame shows around
  // the ball (behind a ball seen from above lies the ground just behind it,
  // which the ball itself hides from the camera: parallax).
  const glm::dvec3 eye{0.12, -0.45, 0.05};
  const MirrorBallView view = kioskView(eye);
  RigGeometry rig;
  rig.probe_center_w = view.center_w;
  rig.probe_radius_m = view.radius_m;
  rig.post_radius_m = 0.003;
  // The frame: each pixel's camera ray, to the ground or the sky (ball and
  // post are excluded by the reader, so what they would show is not needed).
  const LinearPixelReader read = [&](int x, int y, bool& clipped) {
    clipped = false;
    const glm::dvec3 ray_w = glm::transpose(view.pose.R_cam_from_world) * pixelToCameraRay(view.camera, {x, y});
    const glm::dvec3 d = glm::normalize(ray_w);
    if (d.z < 0.0) return groundRadiance(eye + d * (-eye.z / d.z));
    return skyRadiance(d);
  };
  // The ball's samples: every texel the ball shows, at its confidence.
  const int n = 64;
  CubeMapRGB map(n);
  const ProbeObservation ball_only = observeBall(view, map, nullptr, nullptr, 1.0, ObservationSettings{});
  ProbeObservation observation = ball_only;
  const long given = addFrameAroundBall(observation, view, rig, read, ObservationSettings{});
  EXPECT_GT(given, 0);
  const glm::dvec3 behind = glm::normalize(view.center_w - eye);
  const std::size_t per_face = static_cast<std::size_t>(n) * n;
  long blind = 0, blind_filled = 0, checked = 0;
  double worst_ground = 0.0, worst_sky = 0.0;
  for (std::size_t i = 0; i < observation.texelCount(); ++i) {
    const int face = static_cast<int>(i / per_face), local = static_cast<int>(i % per_face);
    const glm::dvec3 r = cubeTexelCenterDirection(face, local % n, local / n, n);
    if (ball_only.confidence[i] == 0.0f) {
      ++blind;
      if (observation.source[i] == 2) ++blind_filled;
    }
    if (observation.source[i] != 2) continue;
    EXPECT_GT(observation.confidence[i], ball_only.confidence[i]);
    ++checked;
    const glm::dvec3 got(observation.radiance.faces[face][local]);
    if (r.z < 0.0) {
      // The ground point the ball sees: the frame read it where it is.
      // Within 1.5 m: further out a pixel spans more of the floor than the
      // texture's half period, and averages what this point value does not.
      const double t = -view.center_w.z / r.z;
      if (t > 1.5) continue;
      const glm::dvec3 truth = groundRadiance(view.center_w + r * t);
      worst_ground = std::max(worst_ground, glm::length(got - truth) / glm::length(truth));
    } else {
      // The sky: no parallax in an infinitely far sky.
      worst_sky = std::max(worst_sky, glm::length(got - skyRadiance(r)) / glm::length(skyRadiance(r)));
    }
    // Never a pixel whose ray passes within the ball's outline.
    EXPECT_GT(std::acos(std::clamp(glm::dot(r, behind), -1.0, 1.0)), std::asin(0.03 / glm::length(view.center_w - eye)))
        << "texel " << i;
  }
  // The blind cone (2 asin(R / D), 7 deg here) holds ~80 texels at 64^2.
  EXPECT_GT(checked, 20);
  EXPECT_LT(worst_ground, 0.03);
  EXPECT_LT(worst_sky, 0.01);
  // The blind spot is a cone of about twice the ball's angular radius
  // behind it; the frame shows all of it but the ball's own disc.
  ASSERT_GT(blind, 0);
  EXPECT_GT(static_cast<double>(blind_filled) / blind, 0.5) << blind_filled << " of " << blind;
}

}  // namespace
}  // namespace probelight::ibl
