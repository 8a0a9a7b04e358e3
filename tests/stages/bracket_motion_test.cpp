// The camera's motion through a bracket: a constant velocity fitted through
// the reference pose, from the frames whose tag gave a pose. Synthetic
// poses of a camera circling the rig at a constant rate, looking at its
// centre, so that every expected pose follows from the motion by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "sim/camera_path.hpp"
#include "stages/bracket_motion.hpp"

namespace probelight {
namespace {

// A camera 0.55 m from the origin, 25 degrees up, at azimuth `azimuth_rad`,
// looking at the origin (the simulator's orbit).
PoseCamFromWorld cameraAt(double azimuth_rad) {
  const glm::dvec3 origin(0.0);
  return sim::lookAtPose(sim::orbitEye(origin, 0.55, 25.0, azimuth_rad * 180.0 / std::numbers::pi), origin);
}

double rotationErrorDeg(const PoseCamFromWorld& a, const PoseCamFromWorld& b) {
  return rotationAngleDeg(a.R_cam_from_world, b.R_cam_from_world);
}

double centreErrorM(const PoseCamFromWorld& a, const PoseCamFromWorld& b) {
  return glm::length(a.cameraCenterWorld() - b.cameraCenterWorld());
}

constexpr double kFrameS = 1.0 / 30.0;
constexpr double kRateRadPerS = 12.0 * std::numbers::pi / 180.0;  // a hand-held sweep

TEST(BracketMotion, FollowsACameraMovingAtAConstantRate) {
  BracketMotion motion(cameraAt(0.0), 10.0);
  motion.addTracked(10.0 + kFrameS, cameraAt(kRateRadPerS * kFrameS));
  motion.addTracked(10.0 + 2 * kFrameS, cameraAt(kRateRadPerS * 2 * kFrameS));
  for (int frame : {3, 4}) {
    const std::optional<PoseCamFromWorld> predicted = motion.poseAt(10.0 + frame * kFrameS);
    ASSERT_TRUE(predicted);
    const PoseCamFromWorld truth = cameraAt(kRateRadPerS * frame * kFrameS);
    // The rotation about the rig's axis is at a constant rate: exact to
    // rounding. The centre moves on a circle, the fit on its chord's line:
    // 0.55 m x (1 - cos(1.6 degrees)) ~ 0.2 mm off, far under the 2 mm the
    // frame moves.
    EXPECT_LT(rotationErrorDeg(*predicted, truth), 1e-6) << "frame " << frame;
    EXPECT_LT(centreErrorM(*predicted, truth), 3e-4) << "frame " << frame;
    EXPECT_GT(centreErrorM(cameraAt(0.0), truth), 5e-3) << "the camera did move";
  }
}

TEST(BracketMotion, AveragesTheTagsScatterThroughTheReference) {
  // A still camera whose dim tags scatter one way and the other: the fit's
  // velocity is their mean over time, not the last one's.
  BracketMotion motion(cameraAt(0.0), 0.0);
  motion.addTracked(kFrameS, cameraAt(0.002));
  motion.addTracked(2 * kFrameS, cameraAt(-0.001));
  const std::optional<PoseCamFromWorld> predicted = motion.poseAt(4 * kFrameS);
  ASSERT_TRUE(predicted);
  // Least squares through the origin: rate = (1 x 0.002 + 2 x -0.001) / 5
  // per frame = 0: the camera stays where the reference was. Its centre to
  // second order (the circle's sag, 0.55 m x 0.002^2 / 2 ~ 1 micrometre;
  // the scatter moved it 1 mm).
  EXPECT_LT(rotationErrorDeg(*predicted, cameraAt(0.0)), 1e-6);
  EXPECT_LT(centreErrorM(*predicted, cameraAt(0.0)), 1e-5);
  EXPECT_GT(centreErrorM(cameraAt(0.002), cameraAt(0.0)), 9e-4);
}

TEST(BracketMotion, WithoutTimesOrTrackedFramesThereIsNoMotion) {
  BracketMotion unknown_reference(cameraAt(0.0), NAN);
  unknown_reference.addTracked(1.0, cameraAt(0.01));
  EXPECT_FALSE(unknown_reference.poseAt(2.0));
  EXPECT_EQ(unknown_reference.trackedCount(), 0);

  BracketMotion known(cameraAt(0.0), 0.0);
  EXPECT_FALSE(known.poseAt(1.0)) << "no tracked frame";
  known.addTracked(NAN, cameraAt(0.01));
  known.addTracked(0.0, cameraAt(0.01));  // the reference's own time says nothing of a rate
  EXPECT_EQ(known.trackedCount(), 0);
  known.addTracked(kFrameS, cameraAt(0.01));
  EXPECT_FALSE(known.poseAt(NAN));
  EXPECT_TRUE(known.poseAt(2 * kFrameS));
}

}  // namespace
}  // namespace probelight
