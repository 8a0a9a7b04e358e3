// Pose, conventions and robustness of TagTracker on rendered frames whose
// truth is known exactly (tag_rendering.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "sim/world.hpp"
#include "tag_rendering.hpp"
#include "test_support.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {
namespace {

using testing::lookAtPose;
using testing::TagScene;
using tracking::TagTracker;
using tracking::TagTrackResult;

// Corner accuracy the tracker must reach on these renders; everything else is
// derived from it. Half a pixel is the accuracy AprilTag's own reference
// corners are held to on real photos (tag_detection_photos_test.cpp).
constexpr double kCornerTolerancePx = 0.5;

CameraIntrinsics boardCamera() {  // board/camera.yaml's template values
  CameraIntrinsics camera;
  camera.fx_px = camera.fy_px = 627.0;
  camera.cx_px = 319.5;
  camera.cy_px = 239.5;
  camera.distortion = {0.02, -0.05, 0.0, 0.0, 0.0};
  return camera;
}

CameraIntrinsics stronglyDistortedCamera() {  // OpenCV's left01..14 calibration (barrel, k1 = -0.27)
  CameraIntrinsics camera;
  camera.fx_px = camera.fy_px = 535.9;
  camera.cx_px = 342.3;
  camera.cy_px = 235.6;
  camera.distortion = {-0.266, -0.0386, 0.00178, -0.00028, 0.238};
  return camera;
}

RigGeometry rigFor(const TagScene& scene) {
  RigGeometry rig;
  rig.tag_size_m = scene.tag_size_m;
  rig.tag_id = scene.tag_id;
  return rig;
}

std::vector<glm::dvec2> trueCorners(const TagScene& scene) {
  auto world = tracking::tagCornersWorld(scene.tag_size_m);
  return testing::projectWorldPoints({world.begin(), world.end()}, scene.pose, scene.camera);
}

// Camera on a sphere around the tag centre: `tilt_deg` from the tag normal,
// `azimuth_deg` around it, image "up" toward `up_w`.
PoseCamFromWorld orbitPose(double distance_m, double tilt_deg, double azimuth_deg, glm::dvec3 up_w = {0, 1, 0},
                           glm::dvec3 target_w = {0, 0, 0}) {
  double tilt = glm::radians(tilt_deg), azimuth = glm::radians(azimuth_deg);
  glm::dvec3 eye = target_w + distance_m * glm::dvec3(std::sin(tilt) * std::cos(azimuth),
                                                      std::sin(tilt) * std::sin(azimuth), std::cos(tilt));
  return lookAtPose(eye, target_w, up_w);
}

struct PoseTolerance {
  double rotation_deg = 0.0;
  double translation_m = 0.0;
};

// Worst-case (first-order) pose error when every corner coordinate may be off
// by `corner_error_px`: the sum over the 8 coordinates of the pose change one
// such shift causes. Computed with OpenCV's iterative PnP, independently of
// the tracker's IPPE path.
PoseTolerance toleranceFromCornerError(const TagScene& scene, double corner_error_px) {
  auto world = tracking::tagCornersWorld(scene.tag_size_m);
  std::vector<cv::Point3d> object;
  for (const glm::dvec3& p : world) object.emplace_back(p.x, p.y, p.z);
  std::vector<glm::dvec2> truth = trueCorners(scene);
  const CameraIntrinsics& cam = scene.camera;
  cv::Matx33d K(cam.fx_px, 0, cam.cx_px, 0, cam.fy_px, cam.cy_px, 0, 0, 1);
  std::vector<double> distortion(cam.distortion.begin(), cam.distortion.end());
  cv::Matx33d R_true;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R_true(r, c) = scene.pose.R_cam_from_world[c][r];
  cv::Vec3d rvec_true, t_true(scene.pose.t_cam_from_world.x, scene.pose.t_cam_from_world.y, scene.pose.t_cam_from_world.z);
  cv::Rodrigues(R_true, rvec_true);

  PoseTolerance tolerance;
  for (int coordinate = 0; coordinate < 8; ++coordinate) {
    std::vector<cv::Point2d> shifted;
    for (const glm::dvec2& p : truth) shifted.emplace_back(p.x, p.y);
    (coordinate % 2 ? shifted[coordinate / 2].y : shifted[coordinate / 2].x) += corner_error_px;
    cv::Vec3d rvec = rvec_true, tvec = t_true;
    cv::solvePnP(object, shifted, K, distortion, rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
    cv::Matx33d R;
    cv::Rodrigues(rvec, R);
    glm::dmat3 R_glm;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) R_glm[c][r] = R(r, c);
    tolerance.rotation_deg += tracking::rotationDifferenceDeg(scene.pose.R_cam_from_world, R_glm);
    tolerance.translation_m += cv::norm(tvec - t_true);
  }
  return tolerance;
}

TagTrackResult trackScene(TagTracker& tracker, const TagScene& scene) {
  cv::Mat frame = testing::renderTagScene(scene);
  return tracker.track(frame.data, frame.cols, frame.rows, static_cast<int>(frame.step));
}

TEST(TagTrackerSynthetic, ExactCornersGiveTheExactPose) {
  // No image involved: checks the IPPE point order and undistortion alone.
  for (const CameraIntrinsics& camera : {boardCamera(), stronglyDistortedCamera()}) {
    TagScene scene;
    scene.camera = camera;
    scene.pose = orbitPose(0.5, 40.0, -70.0, {0.3, 1.0, 0.0}, {0.03, -0.02, 0.0});
    std::vector<glm::dvec2> truth = trueCorners(scene);
    std::vector<tracking::TagPoseSolution> solutions =
        tracking::solveTagPoses({truth[0], truth[1], truth[2], truth[3]}, scene.tag_size_m, camera);
    ASSERT_FALSE(solutions.empty());
    // Only floating-point and the iterative undistortion (converged to 1e-10) remain.
    EXPECT_LT(solutions[0].reprojection_error_px, 1e-6);
    EXPECT_LT(tracking::rotationDifferenceDeg(solutions[0].pose.R_cam_from_world, scene.pose.R_cam_from_world), 1e-7);
    EXPECT_LT(glm::length(solutions[0].pose.t_cam_from_world - scene.pose.t_cam_from_world), 1e-8);
  }
}

TEST(TagTrackerSynthetic, RecoversPoseWithinToleranceDerivedFromCornerAccuracy) {
  struct Case {
    const char* what;
    CameraIntrinsics camera;
    double distance_m, tilt_deg, azimuth_deg;
    glm::dvec3 up_w;
  };
  const Case cases[] = {
      {"kiosk view, tag upright", boardCamera(), 0.45, 40.0, -90.0, {0, 1, 0}},
      {"tag turned 90 deg in the image", boardCamera(), 0.5, 35.0, 0.0, {1, 0, 0}},
      {"tag upside down", boardCamera(), 0.6, 50.0, 90.0, {0, -1, 0}},
      {"tag turned 270 deg", boardCamera(), 0.4, 30.0, 180.0, {-1, 0, 0}},
      {"steep and far", boardCamera(), 0.9, 60.0, -120.0, {0.5, 1, 0}},
      {"strong barrel distortion, tag off-centre", stronglyDistortedCamera(), 0.45, 45.0, -60.0, {0.2, 1, 0}},
  };
  int seed = 1;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    TagScene scene;
    scene.camera = c.camera;
    scene.noise_sigma = 2.0;  // grey levels; a clean indoor sensor
    scene.noise_seed = static_cast<unsigned>(seed++);
    // Aim beside the tag so it does not sit on the optical axis, where distortion vanishes.
    scene.pose = orbitPose(c.distance_m, c.tilt_deg, c.azimuth_deg, c.up_w, {0.04, 0.03, 0.0});
    TagTracker tracker(tracking::TagDetectorSettings{}, rigFor(scene), scene.camera);
    TagTrackResult result = trackScene(tracker, scene);
    ASSERT_TRUE(result.found) << result.status;
    EXPECT_EQ(result.id, scene.tag_id);

    // Corner k must be the image of world corner k: a wrong order is off by a whole edge.
    std::vector<glm::dvec2> truth = trueCorners(scene);
    for (int k = 0; k < 4; ++k)
      EXPECT_LT(glm::length(result.corners_px[k] - truth[k]), kCornerTolerancePx) << "corner " << k;

    PoseTolerance tolerance = toleranceFromCornerError(scene, kCornerTolerancePx);
    double distance_m = glm::length(scene.pose.t_cam_from_world);
    double rotation_error_deg = tracking::rotationDifferenceDeg(result.pose.R_cam_from_world, scene.pose.R_cam_from_world);
    double translation_error_m = glm::length(result.pose.t_cam_from_world - scene.pose.t_cam_from_world);
    EXPECT_LT(rotation_error_deg, tolerance.rotation_deg);
    EXPECT_LT(translation_error_m / distance_m, tolerance.translation_m / distance_m);
    // The reported reprojection error is an RMS of corner distances, so it is
    // bounded by the corner accuracy itself.
    EXPECT_LT(result.reprojection_error_px, kCornerTolerancePx);
    std::printf("[ %-42s ] rotation %.3f deg (tol %.2f), translation %.4f%% of distance (tol %.3f%%), reproj %.3f px\n",
                c.what, rotation_error_deg, tolerance.rotation_deg, 100 * translation_error_m / distance_m,
                100 * tolerance.translation_m / distance_m, result.reprojection_error_px);
  }
}

TEST(TagTrackerSynthetic, WorldAxesFollowThePrintedTagImage) {
  // Camera in front of and above the tag, image "up" toward the printed top.
  TagScene scene;
  scene.camera = boardCamera();
  glm::dvec3 eye_w(0.0, -0.25, 0.40);
  scene.pose = lookAtPose(eye_w, {0, 0, 0}, {0, 1, 0});
  TagTracker tracker(tracking::TagDetectorSettings{}, rigFor(scene), scene.camera);
  TagTrackResult result = trackScene(tracker, scene);
  ASSERT_TRUE(result.found) << result.status;

  // Printed image seen upright: corner 0 (-X,-Y) bottom-left, 1 bottom-right,
  // 2 top-right, 3 top-left (image y grows downward).
  const auto& c = result.corners_px;
  EXPECT_LT(c[0].x, c[1].x);
  EXPECT_LT(c[3].x, c[2].x);
  EXPECT_GT(c[0].y, c[3].y);
  EXPECT_GT(c[1].y, c[2].y);

  // +X goes right in the image, +Y up (against camera y), +Z toward the camera.
  glm::dvec3 x_in_camera = result.pose.R_cam_from_world * glm::dvec3(1, 0, 0);
  glm::dvec3 y_in_camera = result.pose.R_cam_from_world * glm::dvec3(0, 1, 0);
  glm::dvec3 z_in_camera = result.pose.R_cam_from_world * glm::dvec3(0, 0, 1);
  EXPECT_GT(x_in_camera.x, 0.99);  // cos(8 deg): the view is symmetric about x
  EXPECT_LT(y_in_camera.y, 0.0);
  EXPECT_LT(z_in_camera.z, 0.0);   // +Z points back at the camera
  // Camera position in W, to the tolerance the corner accuracy allows.
  PoseTolerance tolerance = toleranceFromCornerError(scene, kCornerTolerancePx);
  glm::dvec3 center_w = result.pose.cameraCenterWorld();
  EXPECT_GT(center_w.z, 0.0);  // above the ground
  EXPECT_LT(glm::length(center_w - eye_w),
            tolerance.translation_m + glm::radians(tolerance.rotation_deg) * glm::length(eye_w));
}

// Slow orbit that starts oblique (unambiguous) and settles `settle_tilt_deg`
// (+- `wobble_deg`) from straight above the tag.
PoseCamFromWorld nearFrontoParallelPose(int frame, double distance_m, double settle_tilt_deg, double wobble_deg) {
  double tilt_deg = frame < 30 ? 20.0 - (20.0 - settle_tilt_deg) * frame / 30.0
                               : settle_tilt_deg + wobble_deg * std::sin(0.25 * (frame - 30));
  return orbitPose(distance_m, tilt_deg, -90.0 + 2.0 * frame);
}

TEST(PoseFlipResolver, NoisyNearFrontoParallelSequenceNeverFlipsToTheOtherSolution) {
  // Corner noise of 0.2 px on a 90 px tag 0.7 m away, 3-5 degrees from
  // fronto-parallel: the two planar solutions lie about 10 degrees apart
  // while each is only about 3 degrees off, so which is on the true side is
  // well defined, yet their reprojection errors differ by less than the noise
  // (measured: lowest-error-wins flips in a few frames of 200).
  CameraIntrinsics camera = boardCamera();
  camera.distortion = {0, 0, 0, 0, 0};
  std::mt19937 rng(2024);
  std::normal_distribution<double> corner_noise_px(0.0, 0.2);
  tracking::PoseFlipResolver resolver(tracking::TagDetectorSettings{}.pose_ambiguity_margin_px);
  int ambiguous_frames = 0, lowest_error_wrong_picks = 0;
  constexpr int kFrames = 200;
  for (int i = 0; i < kFrames; ++i) {
    TagScene scene;
    scene.camera = camera;
    scene.pose = nearFrontoParallelPose(i, 0.7, 4.0, 1.0);
    std::vector<glm::dvec2> truth = trueCorners(scene);
    std::array<glm::dvec2, 4> noisy;
    for (int k = 0; k < 4; ++k) noisy[k] = truth[k] + glm::dvec2(corner_noise_px(rng), corner_noise_px(rng));
    std::vector<tracking::TagPoseSolution> solutions = tracking::solveTagPoses(noisy, scene.tag_size_m, camera);
    ASSERT_EQ(solutions.size(), 2u) << "frame " << i;
    tracking::PoseChoice choice = resolver.choose(solutions);
    const glm::dmat3& truth_R = scene.pose.R_cam_from_world;
    double chosen_error_deg = tracking::rotationDifferenceDeg(solutions[choice.index].pose.R_cam_from_world, truth_R);
    double other_error_deg = tracking::rotationDifferenceDeg(solutions[1 - choice.index].pose.R_cam_from_world, truth_R);
    // Had the resolver taken the mirrored solution, its error would exceed the
    // other's by about the solutions' separation (they lie on opposite sides
    // of the truth). Noise alone moves both by similar amounts, so a
    // difference under half the separation is a tie, not a flip.
    double separation_deg = tracking::rotationDifferenceDeg(solutions[0].pose.R_cam_from_world, solutions[1].pose.R_cam_from_world);
    EXPECT_LT(chosen_error_deg - other_error_deg, separation_deg / 2) << "frame " << i;
    ambiguous_frames += choice.ambiguous;
    double lowest_error_deg = tracking::rotationDifferenceDeg(solutions[0].pose.R_cam_from_world, truth_R);
    double second_error_deg = tracking::rotationDifferenceDeg(solutions[1].pose.R_cam_from_world, truth_R);
    lowest_error_wrong_picks += lowest_error_deg - second_error_deg >= separation_deg / 2;
  }
  std::printf("[ flip, corner noise ] %d frames, %d ambiguous, %d wrong picks by lowest error alone\n", kFrames,
              ambiguous_frames, lowest_error_wrong_picks);
  // The seeded sequence must exercise the temporal choice, including frames
  // where error alone would have flipped.
  EXPECT_GE(ambiguous_frames, 100);
  EXPECT_GE(lowest_error_wrong_picks, 1);
}

TEST(TagTrackerSynthetic, RenderedNearFrontoParallelSequenceStaysOnTheTrueSide) {
  // End to end through detection: a 90 px tag 0.7 m away wobbling 2.5-4.5
  // degrees from fronto-parallel, with sensor noise.
  TagScene scene;
  scene.camera = boardCamera();
  scene.camera.distortion = {0, 0, 0, 0, 0};
  scene.noise_sigma = 3.0;
  TagTracker tracker(tracking::TagDetectorSettings{}, rigFor(scene), scene.camera);
  constexpr int kFrames = 60;
  int ambiguous_frames = 0, merged_frames = 0;
  for (int i = 0; i < kFrames; ++i) {
    scene.pose = nearFrontoParallelPose(i, 0.7, 3.5, 1.0);
    scene.noise_seed = static_cast<unsigned>(100 + i);
    TagTrackResult result = trackScene(tracker, scene);
    ASSERT_TRUE(result.found) << "frame " << i << ": " << result.status;
    const glm::dmat3& truth = scene.pose.R_cam_from_world;
    if (!result.alternative_pose) {
      // Both planar solutions converged to one pose on the bit cells' edges
      // (TagDetectorSettings::refine_corners): the data resolved the
      // ambiguity. The mirrored pose is about twice the 2.5-4.5 deg view
      // angle away, so a flip would be >= 5 deg off; half of that is the bound.
      ++merged_frames;
      EXPECT_LT(tracking::rotationDifferenceDeg(result.pose.R_cam_from_world, truth), 2.5) << "frame " << i;
      continue;
    }
    ambiguous_frames += result.pose_ambiguous;
    // As in PoseFlipResolver's test: a flip would make the chosen error exceed
    // the other's by about the solutions' separation.
    double separation_deg = tracking::rotationDifferenceDeg(result.pose.R_cam_from_world, result.alternative_pose->R_cam_from_world);
    EXPECT_LT(tracking::rotationDifferenceDeg(result.pose.R_cam_from_world, truth) -
                  tracking::rotationDifferenceDeg(result.alternative_pose->R_cam_from_world, truth),
              separation_deg / 2)
        << "frame " << i;
  }
  std::printf("[ flip, rendered ] %d frames, %d ambiguous, %d with one solution left\n", kFrames, ambiguous_frames,
              merged_frames);
  // The sequence must exercise the ambiguity: frames where the corners could
  // not tell the solutions apart, whether history or the bit cells decided.
  EXPECT_GE(ambiguous_frames + merged_frames, 10);
}

TEST(TagTrackerSynthetic, DegenerateFramesDoNotCrash) {
  TagTracker tracker(tracking::TagDetectorSettings{}, RigGeometry{}, boardCamera());
  EXPECT_EQ(tracker.track(nullptr, 640, 480, 640).status_code, tracking::TagTrackStatus::kBadFrame);
  std::vector<std::uint8_t> tiny(16, 0);
  for (int size : {0, 1, 2, 3, 4})
    EXPECT_EQ(tracker.track(tiny.data(), size, size, size).status_code, tracking::TagTrackStatus::kBadFrame) << size;
  EXPECT_EQ(tracker.track(tiny.data(), 4, 4, 2).status_code, tracking::TagTrackStatus::kBadFrame);  // stride < width
  for (std::uint8_t level : {0, 255, 128}) {
    std::vector<std::uint8_t> flat(640 * 480, level);
    TagTrackResult result = tracker.track(flat.data(), 640, 480, 640);
    EXPECT_FALSE(result.found);
    EXPECT_EQ(result.status_code, tracking::TagTrackStatus::kNoTag) << result.status;
  }
  cv::Mat noise(480, 640, CV_8U);
  cv::RNG(7).fill(noise, cv::RNG::UNIFORM, 0, 256);
  EXPECT_FALSE(tracker.track(noise.data, 640, 480, 640).found);
}

TEST(TagTrackerSynthetic, ReportsWrongIdAndReadsPaddedRows) {
  TagScene scene;
  scene.camera = boardCamera();
  scene.pose = orbitPose(0.45, 35.0, -90.0);
  scene.tag_id = 5;
  cv::Mat frame = testing::renderTagScene(scene);

  TagTracker wants_zero(tracking::TagDetectorSettings{}, RigGeometry{}, scene.camera);
  TagTrackResult wrong = wants_zero.track(frame.data, frame.cols, frame.rows, static_cast<int>(frame.step));
  EXPECT_FALSE(wrong.found);
  EXPECT_EQ(wrong.status_code, tracking::TagTrackStatus::kWrongId);
  EXPECT_NE(wrong.status.find("id 5"), std::string::npos) << wrong.status;

  // The same frame inside wider rows (as camera buffers are padded) must give
  // identical corners: the stride is honoured, no pixel is read from padding.
  cv::Mat padded(frame.rows, frame.cols + 96, CV_8U, cv::Scalar(0));
  frame.copyTo(padded(cv::Rect(0, 0, frame.cols, frame.rows)));
  TagTracker wants_five(tracking::TagDetectorSettings{}, rigFor(scene), scene.camera);
  TagTrackResult packed = wants_five.track(frame.data, frame.cols, frame.rows, static_cast<int>(frame.step));
  wants_five.resetHistory();
  TagTrackResult strided = wants_five.track(padded.data, frame.cols, frame.rows, static_cast<int>(padded.step));
  ASSERT_TRUE(packed.found && strided.found) << packed.status << " / " << strided.status;
  for (int k = 0; k < 4; ++k) EXPECT_EQ(packed.corners_px[k], strided.corners_px[k]) << "corner " << k;
}

TEST(TagTrackerSynthetic, RejectsUnknownFamilyAndMismatchedRig) {
  tracking::TagDetectorSettings settings;
  settings.family = "tag99h99";
  EXPECT_THROW(tracking::TagDetector{settings}, std::invalid_argument);
  settings.family = "tag25h9";
  EXPECT_THROW(TagTracker(settings, RigGeometry{}, boardCamera()), std::invalid_argument);  // rig says tag36h11
  for (const std::string& family : tracking::availableTagFamilies()) {
    settings.family = family;
    EXPECT_NO_THROW(tracking::TagDetector{settings}) << family;
  }
}

TEST(RgbToLuma, UsesRec601WeightsInRgbOrder) {
  ImageRGB8 rgb;
  rgb.resize(3, 1);
  const std::uint8_t colours[3][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}};
  for (int x = 0; x < 3; ++x)
    for (int c = 0; c < 3; ++c) rgb.pixels[static_cast<size_t>(x * 3 + c)] = colours[x][c];
  std::vector<std::uint8_t> luma;
  lumaFromRgb(rgb, luma);
  ASSERT_EQ(luma.size(), 3u);
  // Y = 0.299 R + 0.587 G + 0.114 B, rounded to 8 bits (+-1 for fixed-point
  // rounding). Swapped R and B would give 29 for red.
  EXPECT_NEAR(luma[0], 0.299 * 255, 1.0);
  EXPECT_NEAR(luma[1], 0.587 * 255, 1.0);
  EXPECT_NEAR(luma[2], 0.114 * 255, 1.0);
  ImageRGB8 empty;
  lumaFromRgb(empty, luma);
  EXPECT_TRUE(luma.empty());
}

// Bookworm's libapriltag crashes at random with more than one worker thread
// (a fresh detector's first detection, measured: 6 crashes in 6 runs of
// 3,000 detectors): the default must be within what the library survives,
// and more must be refused before libapriltag sees it.
TEST(TagDetectorThreads, DefaultIsSafeAndMoreThanTheLibrarySurvivesIsRefused) {
  EXPECT_LE(tracking::TagDetectorSettings{}.nthreads, tracking::maxDetectorThreads());
  tracking::TagDetectorSettings settings;
  settings.nthreads = tracking::maxDetectorThreads() + 1;
  EXPECT_THROW(tracking::TagDetector detector(settings), std::invalid_argument);
  settings.nthreads = tracking::maxDetectorThreads();
  EXPECT_NO_THROW(tracking::TagDetector detector(settings));
}

// Speed is measured in bench/ (detect_pose), not here. This checks that the
// speed settings the bench compares all still find a kiosk-sized tag.
TEST(TagTrackerSettings, KioskTagIsFoundAtEverySpeedSetting) {
  TagScene scene;
  scene.camera = boardCamera();
  scene.noise_sigma = 2.0;
  scene.pose = orbitPose(0.5, 40.0, -90.0);
  cv::Mat kiosk_frame = testing::renderTagScene(scene);
  struct Variant {
    const char* what;
    float quad_decimate;
    int nthreads;
  };
  const Variant variants[] = {{"defaults", tracking::TagDetectorSettings{}.quad_decimate, tracking::TagDetectorSettings{}.nthreads},
                              {"decimate 1, 1 thread", 1.0f, 1},
                              {"decimate 2, 1 thread", 2.0f, 1},
                              {"decimate 3, 1 thread", 3.0f, 1}};
  for (const Variant& variant : variants) {
    tracking::TagDetectorSettings settings;
    settings.quad_decimate = variant.quad_decimate;
    settings.nthreads = variant.nthreads;
    TagTracker tracker(settings, rigFor(scene), scene.camera);
    const TagTrackResult result =
        tracker.track(kiosk_frame.data, kiosk_frame.cols, kiosk_frame.rows, static_cast<int>(kiosk_frame.step));
    EXPECT_TRUE(result.found) << variant.what << ": " << result.status;
  }
}

}  // namespace
}  // namespace probelight

namespace probelight {
namespace {

// Two tags side by side: each half of the frame is a render whose camera
// looks beside the tag, so each half holds one whole tag.
cv::Mat twoTagFrame(int left_id, int right_id) {
  TagScene left, right;
  left.camera = right.camera = boardCamera();
  left.tag_id = left_id;
  right.tag_id = right_id;
  left.pose = orbitPose(0.6, 0.0, 0.0, {0, 1, 0}, {0.12, 0.0, 0.0});   // tag left of centre
  right.pose = orbitPose(0.6, 0.0, 0.0, {0, 1, 0}, {-0.12, 0.0, 0.0}); // tag right of centre
  cv::Mat frame = testing::renderTagScene(left);
  cv::Mat right_frame = testing::renderTagScene(right);
  right_frame(cv::Rect(320, 0, 320, 480)).copyTo(frame(cv::Rect(320, 0, 320, 480)));
  return frame;
}

TEST(TagTrackerStatus, SeveralTagsWithTheRigsIdAreRefusedOtherIdsIgnored) {
  TagTracker tracker(tracking::TagDetectorSettings{}, RigGeometry{}, boardCamera());
  cv::Mat twins = twoTagFrame(0, 0);
  TagTrackResult refused = tracker.track(twins.data, twins.cols, twins.rows, static_cast<int>(twins.step));
  EXPECT_FALSE(refused.found);
  EXPECT_EQ(refused.status_code, tracking::TagTrackStatus::kSeveralTags) << refused.status;
  EXPECT_EQ(refused.ids_in_view, (std::vector<int>{0, 0}));
  EXPECT_NE(refused.status.find("2 tag36h11 tags with the rig's id 0"), std::string::npos) << refused.status;

  cv::Mat mixed = twoTagFrame(7, 0);
  TagTrackResult found = tracker.track(mixed.data, mixed.cols, mixed.rows, static_cast<int>(mixed.step));
  ASSERT_TRUE(found.found) << found.status;
  EXPECT_EQ(found.id, 0);
  EXPECT_EQ(found.ids_in_view, (std::vector<int>{0, 7}));
  EXPECT_NE(found.status.find("ignored: id 7"), std::string::npos) << found.status;
  EXPECT_GT(found.corners_px[0].x, 320.0) << "the rig's tag is the right-hand one";
  EXPECT_STREQ(tracking::toString(found.status_code), "found");
  EXPECT_STREQ(tracking::toString(refused.status_code), "several_tags");
}

TEST(TagTrackerStatus, ATagLeavingTheFrameIsCutThenGoneAndAnAbsentOneIsJustMissing) {
  // The camera slides along -x, so the tag moves right in the image ~10 px a
  // frame until it is cut by the right edge, and later is out of the frame.
  TagTracker tracker(tracking::TagDetectorSettings{}, RigGeometry{}, boardCamera());
  TagScene scene;
  scene.camera = boardCamera();
  int found = 0, cut = 0, gone = 0, first_cut = -1, last_found = -1;
  for (int frame = 0; frame < 40; ++frame) {
    const double x = -0.01 * frame;
    scene.pose = orbitPose(0.6, 0.0, 0.0, {0, 1, 0}, {x, 0.0, 0.0});
    cv::Mat image = testing::renderTagScene(scene);
    TagTrackResult result = tracker.track(image.data, image.cols, image.rows, static_cast<int>(image.step));
    if (result.found) {
      ++found;
      last_found = frame;
      EXPECT_EQ(cut + gone, 0) << "found again at frame " << frame << " after it was lost";
    } else if (result.status_code == tracking::TagTrackStatus::kCutByFrameEdge) {
      if (first_cut < 0) first_cut = frame;
      ++cut;
      EXPECT_NE(result.status.find("frame edge"), std::string::npos) << result.status;
    } else {
      EXPECT_EQ(result.status_code, tracking::TagTrackStatus::kNoTag) << result.status;
      ++gone;
    }
  }
  std::printf("[ status   ] leaving the frame: %d found, %d cut by the edge, %d gone\n", found, cut, gone);
  // The printed tag is ~130 px wide and moves ~10 px a frame: it is cut for
  // about 13 frames, the first of which straight after the last sighting.
  EXPECT_GE(found, 5);
  EXPECT_EQ(first_cut, last_found + 1);
  EXPECT_GE(cut, 5);
  EXPECT_GE(gone, 1) << "beyond the half-second memory, or wholly outside, it is simply not in view";

  // A tag that vanishes from the middle of the frame (covered) is not "cut".
  TagTracker fresh(tracking::TagDetectorSettings{}, RigGeometry{}, boardCamera());
  scene.pose = orbitPose(0.6, 0.0, 0.0);
  cv::Mat visible = testing::renderTagScene(scene);
  ASSERT_TRUE(fresh.track(visible.data, visible.cols, visible.rows, static_cast<int>(visible.step)).found);
  cv::Mat covered(480, 640, CV_8U, cv::Scalar(110));
  EXPECT_EQ(fresh.track(covered.data, 640, 480, 640).status_code, tracking::TagTrackStatus::kNoTag);
}

}  // namespace
}  // namespace probelight

namespace probelight {
namespace {

// The windowed search (TagDetectorSettings::track_in_window) must find what
// the whole-frame search finds. libapriltag's own corners differ between the
// two by up to 0.11 px (measured; its thresholding and quad fit see another
// image extent). The refiner starts from those and re-fits every edge at
// full resolution, which leaves a difference of the order of the corners'
// noise (0.015 px median, pose_accuracy_test): 0.05 px is three times that.
// One simulated frame's luma plane and truth.
struct SimFrame {
  std::vector<std::uint8_t> luma;
  int width = 0, height = 0;
  FrameTruth truth;
};
SimFrame renderSimFrame(const sim::World& world, std::uint64_t index) {
  SimFrame frame;
  ImageRGB8 image;
  world.render(index, image, frame.truth);
  lumaFromRgb(image, frame.luma);
  frame.width = image.width;
  frame.height = image.height;
  return frame;
}
TagTrackResult trackSimFrame(TagTracker& tracker, const SimFrame& frame) {
  return tracker.track(frame.luma.data(), frame.width, frame.height, frame.width);
}

TEST(TagTrackerWindow, FollowsTheTagInAWindowWithTheSameResultAndFallsBackWhenItJumps) {
  sim::SceneConfig scene = sim::defaultScene();
  sim::World world(scene);
  tracking::TagDetectorSettings windowed_settings, full_settings;
  windowed_settings.family = full_settings.family = scene.rig.tag_family;
  full_settings.track_in_window = false;
  TagTracker windowed(windowed_settings, scene.rig, scene.camera), full(full_settings, scene.rig, scene.camera);
  int windowed_frames = 0;
  double largest_difference_px = 0.0;
  for (std::uint64_t index = 0; index < 35; ++index) {
    const SimFrame frame = renderSimFrame(world, index);
    TagTrackResult a = trackSimFrame(windowed, frame);
    const bool was_windowed = windowed.lastSearchWasWindowed();
    TagTrackResult b = trackSimFrame(full, frame);
    ASSERT_TRUE(a.found && b.found) << "frame " << index << ": " << a.status << " / " << b.status;
    EXPECT_FALSE(full.lastSearchWasWindowed());
    if (was_windowed) ++windowed_frames;
    for (int k = 0; k < 4; ++k) largest_difference_px = std::max(largest_difference_px, glm::length(a.corners_px[k] - b.corners_px[k]));
  }
  std::printf("[ window   ] 35 orbit frames: %d searched in a window; corners differ by at most %.4f px\n",
              windowed_frames, largest_difference_px);
  // The first frame and the 30th-frame full search are whole-frame searches.
  EXPECT_EQ(windowed_frames, 33);
  EXPECT_LT(largest_difference_px, 0.05);

  // Unrelated views one after the other: the window misses, the whole frame is searched.
  scene.camera_path.name = "random";
  sim::World jumping(scene);
  TagTracker tracker(windowed_settings, scene.rig, scene.camera);
  for (std::uint64_t index = 0; index < 6; ++index) {
    const SimFrame frame = renderSimFrame(jumping, index);
    TagTrackResult result = trackSimFrame(tracker, frame);
    EXPECT_TRUE(result.found) << "random view " << index << ": " << result.status;
    EXPECT_LT(tracking::rotationDifferenceDeg(result.pose.R_cam_from_world, frame.truth.pose.R_cam_from_world), 0.3);
  }
}

// A tracker seeded with a pose found by another (as a bracket's tracker is
// with the kiosk's, for the frames taken right after) searches a window at
// its first frame, and finds what a whole-frame search finds there (the
// tolerance above); seeded with a pose far from the tag, the window misses
// and it falls back to the whole frame, still finding it.
TEST(TagTrackerWindow, ASeededTrackerSearchesAWindowAtItsFirstFrame) {
  sim::SceneConfig scene = sim::defaultScene();
  sim::World world(scene);
  tracking::TagDetectorSettings settings;
  settings.family = scene.rig.tag_family;
  TagTracker full(settings, scene.rig, scene.camera);
  const SimFrame first = renderSimFrame(world, 0), next = renderSimFrame(world, 1);
  const TagTrackResult found = trackSimFrame(full, first);
  ASSERT_TRUE(found.found) << found.status;
  EXPECT_FALSE(full.lastSearchWasWindowed());
  const TagTrackResult reference = trackSimFrame(full, next);
  ASSERT_TRUE(reference.found);

  TagTracker seeded(settings, scene.rig, scene.camera);
  seeded.seed(found.pose);
  const TagTrackResult result = trackSimFrame(seeded, next);
  ASSERT_TRUE(result.found) << result.status;
  EXPECT_TRUE(seeded.lastSearchWasWindowed());
  for (int k = 0; k < 4; ++k) EXPECT_LT(glm::length(result.corners_px[k] - reference.corners_px[k]), 0.05) << k;

  // Seeded a metre to the side: the tag is not in that window.
  PoseCamFromWorld elsewhere = found.pose;
  elsewhere.t_cam_from_world.x += 1.0;
  TagTracker misled(settings, scene.rig, scene.camera);
  misled.seed(elsewhere);
  const TagTrackResult recovered = trackSimFrame(misled, next);
  ASSERT_TRUE(recovered.found) << recovered.status;
  EXPECT_FALSE(misled.lastSearchWasWindowed());
  EXPECT_LT(tracking::rotationDifferenceDeg(recovered.pose.R_cam_from_world, next.truth.pose.R_cam_from_world), 0.3);
}

}  // namespace
}  // namespace probelight
