// Lights move to a new fit over the fade time without a pop: synthetic
// sequences of fits against the frame-by-frame change of what is shown.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "stages/light_transition.hpp"

namespace probelight {
namespace {

ibl::DomeLight light(double azimuth_deg, double elevation_deg, double brightness) {
  const double a = glm::radians(azimuth_deg), e = glm::radians(elevation_deg);
  ibl::DomeLight l;
  l.direction_w = {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
  l.rgb = glm::dvec3(brightness);
  l.spread_rad = 0.2;
  return l;
}

double upIrradiance(const std::vector<ibl::DomeLight>& lights) {
  double sum = 0.0;
  for (const ibl::DomeLight& l : lights) sum += l.rgb.g * std::max(0.0, l.direction_w.z);
  return sum;
}

std::vector<ibl::DomeLight> fitA() { return {light(0, 30, 1.0), light(90, 50, 0.5), light(180, 20, 0.2), light(270, 70, 0.1)}; }
std::vector<ibl::DomeLight> fitB() { return {light(20, 35, 0.3), light(100, 45, 1.5), light(200, 25, 0.4), light(280, 60, 0.1)}; }

constexpr double kFramePeriodS = 1.0 / 30.0;
constexpr double kFadeS = 0.5;  // 15 frames

TEST(LightTransition, FirstFitShowsAtOnce) {
  LightTransition transition(kFadeS);
  transition.retarget(fitA(), 10.0);
  EXPECT_FALSE(transition.empty());
  const auto shown = transition.at(10.0);
  ASSERT_EQ(shown.size(), 4u);
  EXPECT_DOUBLE_EQ(upIrradiance(shown), upIrradiance(fitA()));
}

TEST(LightTransition, NewFitFadesInOverTheFadeTimeWithoutAPop) {
  LightTransition transition(kFadeS);
  transition.retarget(fitA(), 0.0);
  transition.retarget(fitB(), 1.0);
  // At the moment of the new fit nothing has moved yet.
  EXPECT_NEAR(upIrradiance(transition.at(1.0)), upIrradiance(fitA()), 1e-12);
  const double total_change = std::abs(upIrradiance(fitB()) - upIrradiance(fitA()));
  std::vector<ibl::DomeLight> previous = transition.at(1.0);
  for (int frame = 1; frame <= 20; ++frame) {
    const double now = 1.0 + frame * kFramePeriodS;
    const std::vector<ibl::DomeLight> shown = transition.at(now);
    ASSERT_EQ(shown.size(), previous.size());
    // Linear in time: each frame moves the ground's irradiance by at most a
    // 15th of the whole change (plus the slerp's direction effect on z,
    // bounded by the same share of the angle: a small margin).
    EXPECT_LE(std::abs(upIrradiance(shown) - upIrradiance(previous)), total_change / 15.0 * 1.5 + 1e-12) << frame;
    for (std::size_t i = 0; i < shown.size(); ++i) {
      const double turn = std::acos(std::clamp(glm::dot(shown[i].direction_w, previous[i].direction_w), -1.0, 1.0));
      EXPECT_LE(turn, glm::radians(60.0) / 15.0) << "light " << i << " frame " << frame;  // no pair is 60 deg apart here
    }
    EXPECT_EQ(transition.moving(now), frame * kFramePeriodS < kFadeS) << frame;
    previous = shown;
  }
  // Done: exactly the new fit.
  EXPECT_NEAR(upIrradiance(transition.at(2.0)), upIrradiance(fitB()), 1e-12);
}

TEST(LightTransition, FewerOrMoreLightsFadeOutOrIn) {
  LightTransition transition(kFadeS);
  transition.retarget(fitA(), 0.0);
  std::vector<ibl::DomeLight> two = {fitB()[0], fitB()[1]};
  transition.retarget(two, 1.0);
  EXPECT_EQ(transition.at(1.0).size(), 4u);
  EXPECT_NEAR(upIrradiance(transition.at(1.0)), upIrradiance(fitA()), 1e-12);
  EXPECT_EQ(transition.at(1.0 + kFadeS).size(), 2u) << "the two left over have faded out and are gone";
  EXPECT_NEAR(upIrradiance(transition.at(1.0 + kFadeS)), upIrradiance(two), 1e-12);
  transition.retarget(fitA(), 3.0);
  EXPECT_EQ(transition.at(3.0).size(), 4u);
  EXPECT_NEAR(upIrradiance(transition.at(3.0)), upIrradiance(two), 1e-12) << "the new ones start black";
}

// A new fit arriving while a fade is under way (the lights changing during a
// recalibration) starts from what is shown then: no jump.
TEST(LightTransition, RetargetMidFadeStartsFromWhatIsShown) {
  LightTransition transition(kFadeS);
  transition.retarget(fitA(), 0.0);
  transition.retarget(fitB(), 1.0);
  const double mid = 1.0 + 0.4 * kFadeS;
  const double shown_before = upIrradiance(transition.at(mid));
  transition.retarget(fitA(), mid);
  EXPECT_NEAR(upIrradiance(transition.at(mid)), shown_before, 1e-12);
  EXPECT_NEAR(upIrradiance(transition.at(mid + kFadeS)), upIrradiance(fitA()), 1e-12);
}

TEST(LightTransition, ZeroFadeSwitchesAtOnceAndBlendHandlesOppositeDirections) {
  LightTransition transition(0.0);
  transition.retarget(fitA(), 0.0);
  transition.retarget(fitB(), 1.0);
  EXPECT_NEAR(upIrradiance(transition.at(1.0)), upIrradiance(fitB()), 1e-12);
  EXPECT_FALSE(transition.moving(1.0));
  ibl::DomeLight a = light(0, 0, 1.0), b = light(180, 0, 1.0);  // exactly opposite
  const ibl::DomeLight half = blendLights(a, b, 0.5);
  EXPECT_TRUE(std::isfinite(half.direction_w.x) && std::isfinite(half.direction_w.z));
  EXPECT_NEAR(glm::length(half.direction_w), 1.0, 1e-9);
}

}  // namespace
}  // namespace probelight
