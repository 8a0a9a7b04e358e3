// MapUpdatePolicy on synthetic frame sequences: a ball image drawn into a
// luma plane with camera-like noise, and an outline that the test moves (or
// jitters, as pose noise does) independently of the image.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "stages/map_update_policy.hpp"

namespace probelight {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;
// The simulator's default camera noise, per pixel, in codes.
constexpr double kNoiseSigma = 1.5;

struct Lamp {
  glm::dvec2 offset{0.0};  // from the ball centre, px
  double radius_px = 0.0;  // 0: off
};

// A ball image with sharp edges everywhere (vertical stripes 4 px wide,
// codes 60 and 200, the kind of contrast a soft box's edge gives), on a grey
// floor, plus Gaussian noise from `rng`. Sharp edges make the test strict:
// a 0.3 px shift of a grid across them changes many cells by tens of codes.
std::vector<std::uint8_t> drawBall(glm::dvec2 center, double radius, std::mt19937& rng, Lamp lamp = {}) {
  std::normal_distribution<double> noise(0.0, kNoiseSigma);
  std::vector<std::uint8_t> luma(kWidth * kHeight);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const glm::dvec2 p(x, y);
      double value = 90.0;  // floor
      if (glm::length(p - center) <= radius) value = (static_cast<int>(std::floor((x - center.x) / 4.0)) & 1) ? 200 : 60;
      if (lamp.radius_px > 0.0 && glm::length(p - center - lamp.offset) <= lamp.radius_px) value = 255.0;
      luma[y * kWidth + x] = static_cast<std::uint8_t>(std::clamp(std::lround(value + noise(rng)), 0L, 255L));
    }
  }
  return luma;
}

glm::dmat3 rotationAboutZ(double degrees) {
  const double a = degrees * M_PI / 180.0;
  return glm::dmat3(std::cos(a), std::sin(a), 0.0, -std::sin(a), std::cos(a), 0.0, 0.0, 0.0, 1.0);
}

MapFrameInput frameInput(const std::vector<std::uint8_t>& luma, glm::dvec2 center, double radius,
                         double rotation_deg = 0.0) {
  MapFrameInput input;
  input.tag_found = true;
  input.outline.valid = true;
  input.outline.center_px = center;
  input.outline.radius_px = radius;
  input.outline.min_px = center - radius;
  input.outline.max_px = center + radius;
  input.outline.fully_in_image = true;
  input.rotation_cam_from_world = rotationAboutZ(rotation_deg);
  input.luma = LumaView{luma.data(), kWidth, kHeight, kWidth};
  return input;
}

const glm::dvec2 kCenter(160.3, 120.6);
constexpr double kRadius = 30.0;  // the default scene's ball

// The seed's jitter problem: a steady camera, constant light, fresh noise
// every frame, and pose noise that moves the outline by up to 0.3 px (the
// tracker's frame-to-frame noise: 0.04 px p95 on a static camera, 0.5 px p95
// on the default orbit). The maps must not be remade every frame: only the
// first, then once per max age.
TEST(MapUpdatePolicy, SteadyUnchangedViewSkipsButRefreshesAtMaxAge) {
  MapUpdatePolicy policy;
  const int max_age = policy.settings().max_age_frames;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3 / std::sqrt(2.0), 0.3 / std::sqrt(2.0));
  std::vector<int> updates;
  for (int frame = 0; frame < 3 * max_age + 5; ++frame) {
    const auto luma = drawBall(kCenter, kRadius, rng);
    const glm::dvec2 outline_center = kCenter + glm::dvec2(jitter(rng), jitter(rng));
    const MapUpdateDecision decision = policy.decide(frameInput(luma, outline_center, kRadius));
    if (decision.update) {
      updates.push_back(frame);
      EXPECT_EQ(decision.cause, frame == 0 ? MapUpdateCause::kFirst : MapUpdateCause::kMaxAge) << frame;
      EXPECT_FLOAT_EQ(decision.new_weight, frame == 0 ? 1.0f : 0.5f) << "first update is never smoothed into black";
    } else {
      EXPECT_EQ(decision.skip, MapSkipReason::kImageUnchanged) << frame;
      ASSERT_TRUE(decision.image_change_code.has_value());
      EXPECT_LT(*decision.image_change_code, policy.settings().change_threshold_code) << frame;
    }
  }
  EXPECT_EQ(updates, (std::vector<int>{0, max_age, 2 * max_age, 3 * max_age}));
}

// Camera noise alone, on the same grid: the mean |difference| of cell means
// stays under the per-pixel bound 2 sigma / sqrt(pi) (= 1.69), and far under
// the default threshold, even for single-pixel cells.
TEST(MapUpdatePolicy, NoiseAloneStaysUnderTheThreshold) {
  std::mt19937 rng(3);
  for (const double radius : {8.0, 30.0}) {
    const auto a = drawBall(kCenter, radius, rng);
    const auto b = drawBall(kCenter, radius, rng);
    const LumaView va{a.data(), kWidth, kHeight, kWidth};
    const LumaView vb{b.data(), kWidth, kHeight, kWidth};
    const auto difference =
        signatureDifference(sampleBallSignature(va, kCenter, radius), sampleBallSignature(vb, kCenter, radius));
    ASSERT_TRUE(difference.has_value());
    EXPECT_GT(*difference, 0.0) << radius;
    EXPECT_LT(*difference, 2.0 * kNoiseSigma / std::sqrt(M_PI)) << radius;
    EXPECT_LT(*difference, MapUpdateSettings{}.change_threshold_code) << radius;
  }
  // And the measure does see the stripes move: half a stripe (2 px) is a
  // change of tens of codes.
  const auto a = drawBall(kCenter, kRadius, rng);
  const auto b = drawBall(kCenter + glm::dvec2(2.0, 0.0), kRadius, rng);
  const LumaView va{a.data(), kWidth, kHeight, kWidth};
  const LumaView vb{b.data(), kWidth, kHeight, kWidth};
  EXPECT_GT(*signatureDifference(sampleBallSignature(va, kCenter, kRadius), sampleBallSignature(vb, kCenter, kRadius)),
            20.0);
}

// A camera that moves: the ball image changes every frame, but a moving
// frame (blurred, pose lagging) must not become the map. Each of the three
// measures on its own, just above its threshold, is "moving"; just below
// (with the image not changing) is not.
TEST(MapUpdatePolicy, MovingCameraSkipsWithCameraMoving) {
  const MapUpdateSettings settings;
  struct Motion {
    const char* name;
    glm::dvec2 shift_per_frame;
    double radius_change_per_frame;
    double rotation_deg_per_frame;
  };
  const Motion motions[] = {
      {"centre", {settings.max_center_shift_px * 1.2, 0.0}, 0.0, 0.0},
      {"radius", {0.0, 0.0}, settings.max_radius_change_px * 1.2, 0.0},
      {"rotation", {0.0, 0.0}, 0.0, settings.max_rotation_change_deg * 1.2},
  };
  for (const Motion& motion : motions) {
    MapUpdatePolicy policy(settings);
    std::mt19937 rng(11);
    for (int frame = 0; frame < 8; ++frame) {
      const glm::dvec2 center = kCenter + static_cast<double>(frame) * motion.shift_per_frame;
      const double radius = kRadius + frame * motion.radius_change_per_frame;
      const auto luma = drawBall(center, radius, rng);
      const MapUpdateDecision decision =
          policy.decide(frameInput(luma, center, radius, frame * motion.rotation_deg_per_frame));
      if (frame == 0) {
        EXPECT_TRUE(decision.update) << motion.name << ": the first map is made whatever the motion";
      } else {
        EXPECT_FALSE(decision.update) << motion.name << " frame " << frame;
        EXPECT_EQ(decision.skip, MapSkipReason::kCameraMoving) << motion.name << " frame " << frame;
      }
    }
  }
  // Slower than the thresholds, the image unchanged: not moving.
  MapUpdatePolicy policy(settings);
  std::mt19937 rng(12);
  for (int frame = 0; frame < 4; ++frame) {
    const auto luma = drawBall(kCenter, kRadius, rng);
    const double f = frame;
    const MapUpdateDecision decision =
        policy.decide(frameInput(luma, kCenter + f * glm::dvec2(0.8 * settings.max_center_shift_px, 0.0),
                                 kRadius + f * 0.8 * settings.max_radius_change_px,
                                 f * 0.8 * settings.max_rotation_change_deg));
    if (frame > 0) {
      EXPECT_EQ(decision.skip, MapSkipReason::kImageUnchanged) << frame;
    }
  }
}

// A lamp switches on with the camera steady: the next frame updates, and the
// policy keeps updating (smoothed) until the blended reference matches the
// image, then goes back to "unchanged".
TEST(MapUpdatePolicy, LampSwitchingOnWithASteadyCameraUpdatesUntilConverged) {
  MapUpdatePolicy policy;
  const MapUpdateSettings& settings = policy.settings();
  std::mt19937 rng(5);
  const Lamp lamp{{-8.0, -6.0}, 6.0};  // a lamp's image about 12 px across: ~4% of the ball
  const int lamp_on = 10;
  std::vector<int> updates;
  double change_at_switch = 0.0;
  for (int frame = 0; frame < lamp_on + 15; ++frame) {
    const auto luma = drawBall(kCenter, kRadius, rng, frame >= lamp_on ? lamp : Lamp{});
    const MapUpdateDecision decision = policy.decide(frameInput(luma, kCenter, kRadius));
    if (frame == lamp_on) {
      ASSERT_TRUE(decision.update);
      EXPECT_EQ(decision.cause, MapUpdateCause::kImageChanged);
      EXPECT_FLOAT_EQ(decision.new_weight, static_cast<float>(settings.smoothing_new_weight));
      change_at_switch = *decision.image_change_code;
    }
    if (decision.update) updates.push_back(frame);
  }
  ASSERT_GT(change_at_switch, settings.change_threshold_code);
  // After k smoothed updates the reference is (1 - w)^k of the step away;
  // updating stops at the first k where that is under the threshold.
  const double w = settings.smoothing_new_weight;
  const int expected_updates =
      static_cast<int>(std::ceil(std::log(settings.change_threshold_code / change_at_switch) / std::log(1.0 - w)));
  std::vector<int> expected = {0};
  for (int k = 0; k < expected_updates; ++k) expected.push_back(lamp_on + k);
  EXPECT_EQ(updates, expected) << "change at the switch: " << change_at_switch << " codes";
}

TEST(MapUpdatePolicy, EachUnusableFrameSaysWhy) {
  MapUpdatePolicy policy;
  std::mt19937 rng(9);
  const auto luma = drawBall(kCenter, kRadius, rng);

  MapFrameInput no_tag = frameInput(luma, kCenter, kRadius);
  no_tag.tag_found = false;
  EXPECT_EQ(policy.decide(no_tag).skip, MapSkipReason::kNoTag);

  MapFrameInput clipped = frameInput(luma, kCenter, kRadius);
  clipped.outline.fully_in_image = false;
  EXPECT_EQ(policy.decide(clipped).skip, MapSkipReason::kBallNotInView);

  MapFrameInput behind = frameInput(luma, kCenter, kRadius);
  behind.outline.valid = false;
  EXPECT_EQ(policy.decide(behind).skip, MapSkipReason::kBallNotInView);

  const double small = policy.settings().min_probe_radius_px * 0.9;
  const auto small_luma = drawBall(kCenter, small, rng);
  EXPECT_EQ(policy.decide(frameInput(small_luma, kCenter, small)).skip, MapSkipReason::kBallTooSmall);
  EXPECT_FALSE(policy.haveMaps());

  // The first usable frame makes the maps.
  const MapUpdateDecision first = policy.decide(frameInput(luma, kCenter, kRadius));
  EXPECT_TRUE(first.update);
  EXPECT_EQ(first.cause, MapUpdateCause::kFirst);
  EXPECT_STREQ(toString(MapSkipReason::kNoTag), "no tag");
  EXPECT_STREQ(toString(MapSkipReason::kBallNotInView), "ball not fully in view");
  EXPECT_STREQ(toString(MapSkipReason::kBallTooSmall), "ball too small");
  EXPECT_STREQ(toString(MapSkipReason::kCameraMoving), "camera moving");
  EXPECT_STREQ(toString(MapSkipReason::kImageUnchanged), "ball image unchanged");
}

// After the tag was lost, steadiness is unknown until two consecutive frames
// agree: the first frame back is "camera moving" (a hand may still be in the
// way), the second may update.
TEST(MapUpdatePolicy, SteadinessRestartsAfterTheTagIsLost) {
  MapUpdatePolicy policy;
  std::mt19937 rng(13);
  EXPECT_TRUE(policy.decide(frameInput(drawBall(kCenter, kRadius, rng), kCenter, kRadius)).update);
  MapFrameInput lost = frameInput(drawBall(kCenter, kRadius, rng), kCenter, kRadius);
  lost.tag_found = false;
  EXPECT_EQ(policy.decide(lost).skip, MapSkipReason::kNoTag);
  // Back, with different light (so "unchanged" cannot hide the rule).
  const Lamp lamp{{5.0, 5.0}, 8.0};
  EXPECT_EQ(policy.decide(frameInput(drawBall(kCenter, kRadius, rng, lamp), kCenter, kRadius)).skip,
            MapSkipReason::kCameraMoving);
  const MapUpdateDecision second = policy.decide(frameInput(drawBall(kCenter, kRadius, rng, lamp), kCenter, kRadius));
  EXPECT_TRUE(second.update);
  EXPECT_EQ(second.cause, MapUpdateCause::kImageChanged);
}

// A recalibration asks for a fresh map: the next steady frame replaces the
// maps (weight 1) though its image is unchanged; a moving frame does not.
TEST(MapUpdatePolicy, FreshMapRequestUpdatesUnsmoothedOnTheNextSteadyFrame) {
  MapUpdatePolicy policy;
  std::mt19937 rng(17);
  for (int frame = 0; frame < 3; ++frame) policy.decide(frameInput(drawBall(kCenter, kRadius, rng), kCenter, kRadius));
  policy.requestFreshMap();
  const glm::dvec2 moved = kCenter + glm::dvec2(5.0, 0.0);
  EXPECT_EQ(policy.decide(frameInput(drawBall(moved, kRadius, rng), moved, kRadius)).skip, MapSkipReason::kCameraMoving);
  const MapUpdateDecision fresh = policy.decide(frameInput(drawBall(moved, kRadius, rng), moved, kRadius));
  EXPECT_TRUE(fresh.update);
  EXPECT_EQ(fresh.cause, MapUpdateCause::kFreshRequested);
  EXPECT_FLOAT_EQ(fresh.new_weight, 1.0f);
  // Served once: the next unchanged frame is skipped again.
  EXPECT_EQ(policy.decide(frameInput(drawBall(moved, kRadius, rng), moved, kRadius)).skip,
            MapSkipReason::kImageUnchanged);
}

// A ball of one level (255: blown out; 0: covered or black) on the grey
// floor, with Gaussian noise of `sigma` codes added before the 8-bit clip,
// which is what pulls a clipped area's pixels below 255 (or above 0): the
// conservative model (a real sensor clips after its noise and reads 255).
std::vector<std::uint8_t> drawUniformBall(glm::dvec2 center, double radius, double level, double sigma,
                                          std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<std::uint8_t> luma(kWidth * kHeight);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const double value = glm::length(glm::dvec2(x, y) - center) <= radius ? level : 90.0;
      luma[y * kWidth + x] = static_cast<std::uint8_t>(std::clamp(std::lround(value + noise(rng)), 0L, 255L));
    }
  return luma;
}

// A blown-out or covered ball is skipped with its own reason, and the maps
// and their reference survive: the next normal frame, showing what the maps
// hold, is "unchanged", not an update back from white or black.
TEST(MapUpdatePolicy, SaturatedOrDarkBallIsSkippedAndTheMapsKept) {
  for (const double level : {255.0, 0.0}) {
    const MapSkipReason expected = level > 0.0 ? MapSkipReason::kBallSaturated : MapSkipReason::kBallDark;
    MapUpdatePolicy policy;
    std::mt19937 rng(21);
    ASSERT_TRUE(policy.decide(frameInput(drawBall(kCenter, kRadius, rng), kCenter, kRadius)).update);
    for (int frame = 0; frame < 5; ++frame) {
      // sigma 6 codes (4x the simulator's) on the default ball's ~20-pixel cells.
      const MapUpdateDecision decision =
          policy.decide(frameInput(drawUniformBall(kCenter, kRadius, level, 6.0, rng), kCenter, kRadius));
      EXPECT_FALSE(decision.update) << level;
      EXPECT_EQ(decision.skip, expected) << level;
      EXPECT_STREQ(toString(decision.skip), level > 0.0 ? "ball saturated" : "ball dark");
      ASSERT_TRUE(decision.saturated_fraction && decision.dark_fraction);
      EXPECT_GE(level > 0.0 ? *decision.saturated_fraction : *decision.dark_fraction, kUnusableCellFraction);
      EXPECT_TRUE(policy.haveMaps());
      EXPECT_EQ(policy.framesSinceUpdate(), frame + 1) << "the maps were not replaced";
    }
    // Back to the view the maps hold: unchanged, so the reference survived.
    const MapUpdateDecision back = policy.decide(frameInput(drawBall(kCenter, kRadius, rng), kCenter, kRadius));
    EXPECT_EQ(back.skip, MapSkipReason::kImageUnchanged) << level;
  }
}

// Before any map exists, a white or black ball still gives none: the object
// stays hidden rather than lit uniformly white or black; the first usable
// frame then makes the first map.
TEST(MapUpdatePolicy, UnusableBallNeverMakesTheFirstMap) {
  MapUpdatePolicy policy;
  std::mt19937 rng(22);
  // The smallest ball the default settings accept, one-pixel cells, at the
  // simulator's noise: a clipped pixel reads >= 250 with probability 99.95%
  // (5 codes = 3.3 sigma), so well over 95% of cells count.
  const double radius = MapUpdateSettings{}.min_probe_radius_px;
  EXPECT_EQ(policy.decide(frameInput(drawUniformBall(kCenter, radius, 255.0, kNoiseSigma, rng), kCenter, radius)).skip,
            MapSkipReason::kBallSaturated);
  EXPECT_EQ(policy.decide(frameInput(drawUniformBall(kCenter, radius, 0.0, kNoiseSigma, rng), kCenter, radius)).skip,
            MapSkipReason::kBallDark);
  EXPECT_FALSE(policy.haveMaps());
  const MapUpdateDecision first = policy.decide(frameInput(drawBall(kCenter, radius, rng), kCenter, radius));
  EXPECT_TRUE(first.update);
  EXPECT_EQ(first.cause, MapUpdateCause::kFirst);
}

// The thresholds on hand-made signatures: >= 95% of the cells holding pixels,
// cells >= 250 (saturated) or <= 5 (dark); empty cells do not count.
TEST(MapUpdatePolicy, ExposureThresholdsAtTheirEdges) {
  auto signature = [](int cells, int at_level, float level, float rest) {
    BallSignature s;
    s.mean.assign(BallSignature::kCells * BallSignature::kCells, 0.0f);
    s.count.assign(s.mean.size(), 0);  // the rest: off the disc
    for (int i = 0; i < cells; ++i) {
      s.count[i] = 3;
      s.mean[i] = i < at_level ? level : rest;
    }
    return s;
  };
  EXPECT_DOUBLE_EQ(measureBallExposure(signature(100, 95, 250.0f, 120.0f)).saturated_fraction, 0.95);
  EXPECT_DOUBLE_EQ(measureBallExposure(signature(100, 95, 249.9f, 120.0f)).saturated_fraction, 0.0);
  EXPECT_DOUBLE_EQ(measureBallExposure(signature(100, 94, 255.0f, 120.0f)).saturated_fraction, 0.94);
  EXPECT_DOUBLE_EQ(measureBallExposure(signature(100, 95, 5.0f, 120.0f)).dark_fraction, 0.95);
  EXPECT_DOUBLE_EQ(measureBallExposure(signature(100, 95, 5.1f, 120.0f)).dark_fraction, 0.0);
  EXPECT_EQ(measureBallExposure(signature(100, 0, 0.0f, 120.0f)).cells, 100);
  EXPECT_EQ(measureBallExposure(BallSignature{}).cells, 0);
}

// What must not be called unusable: a bright ball with a real structure
// (a dark window across 1/4 of it), and a dark room with one lamp. Both
// update (image changed) instead.
TEST(MapUpdatePolicy, MostlyBrightOrMostlyDarkBallWithStructureIsUsed) {
  for (const double level : {255.0, 0.0}) {
    MapUpdatePolicy policy;
    std::mt19937 rng(23);
    ASSERT_TRUE(policy.decide(frameInput(drawBall(kCenter, kRadius, rng), kCenter, kRadius)).update);
    auto luma = drawUniformBall(kCenter, kRadius, level, kNoiseSigma, rng);
    // A quarter of the disc (x < centre - 0.35 r holds ~1/4 of its area) at
    // mid-grey: well over 5% of the cells.
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x)
        if (glm::length(glm::dvec2(x, y) - kCenter) <= kRadius && x < kCenter.x - 0.35 * kRadius)
          luma[y * kWidth + x] = 120;
    const MapUpdateDecision decision = policy.decide(frameInput(luma, kCenter, kRadius));
    EXPECT_TRUE(decision.update) << level << " " << toString(decision.skip);
    EXPECT_EQ(decision.cause, MapUpdateCause::kImageChanged);
  }
}

// A degenerate pose (NaN) gives a NaN outline or rotation: skipped as "ball
// not fully in view", no undefined sampling, and the next good frame's
// steadiness is not judged against it.
TEST(MapUpdatePolicy, NonFiniteOutlineOrRotationIsSkipped) {
  MapUpdatePolicy policy;
  std::mt19937 rng(24);
  const auto luma = drawBall(kCenter, kRadius, rng);
  ASSERT_TRUE(policy.decide(frameInput(luma, kCenter, kRadius)).update);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (int field = 0; field < 4; ++field) {
    MapFrameInput input = frameInput(luma, kCenter, kRadius);
    if (field == 0) input.outline.center_px.x = nan;
    if (field == 1) input.outline.radius_px = inf;
    if (field == 2) input.outline.center_px.y = -inf;
    if (field == 3) input.rotation_cam_from_world[2][1] = nan;
    const MapUpdateDecision decision = policy.decide(input);
    EXPECT_FALSE(decision.update) << field;
    EXPECT_EQ(decision.skip, MapSkipReason::kBallNotInView) << field;
    EXPECT_FALSE(decision.center_shift_px.has_value()) << field;
  }
  EXPECT_TRUE(policy.haveMaps());
  // The signature of a non-finite outline holds no pixel (and reads none).
  const BallSignature empty = sampleBallSignature(LumaView{luma.data(), kWidth, kHeight, kWidth}, {nan, 3.0}, 10.0);
  EXPECT_EQ(measureBallExposure(empty).cells, 0);
}

}  // namespace
}  // namespace probelight
