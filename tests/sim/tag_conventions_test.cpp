// The rendered tag must agree with the real libapriltag detector about what W
// is: its id decodes, and its corners land where the world corners project.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

extern "C" {
#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
}

#include "sim/scene_geometry.hpp"
#include "sim/tag_pattern.hpp"
#include "sim/world.hpp"

namespace probelight::sim {
namespace {

constexpr double kApriltagPixelCentre = 0.5;

struct Detection {
  int id = -1;
  std::array<glm::dvec2, 4> corners_px;
};

std::vector<Detection> detectTag36h11(const ImageRGB8& rgb) {
  std::vector<std::uint8_t> gray(static_cast<size_t>(rgb.width) * rgb.height);
  for (size_t i = 0; i < gray.size(); ++i)
    gray[i] = static_cast<std::uint8_t>(
        (299 * rgb.pixels[i * 3] + 587 * rgb.pixels[i * 3 + 1] + 114 * rgb.pixels[i * 3 + 2] + 500) / 1000);
  image_u8_t image{rgb.width, rgb.height, rgb.width, gray.data()};
  apriltag_family_t* family = tag36h11_create();
  apriltag_detector_t* detector = apriltag_detector_create();
  apriltag_detector_add_family(detector, family);
  detector->quad_decimate = 1.0f;  // full resolution: corner accuracy is the point here
  detector->nthreads = 1;
  zarray_t* found = apriltag_detector_detect(detector, &image);
  std::vector<Detection> result;
  for (int i = 0; i < zarray_size(found); ++i) {
    apriltag_detection_t* det;
    zarray_get(found, i, &det);
    Detection d;
    d.id = det->id;
    for (int c = 0; c < 4; ++c) d.corners_px[c] = {det->p[c][0], det->p[c][1]};
    result.push_back(d);
  }
  apriltag_detections_destroy(found);
  apriltag_detector_destroy(detector);
  tag36h11_destroy(family);
  return result;
}

void expectCornersMatch(const World& world, std::uint64_t frame) {
  ImageRGB8 image;
  FrameTruth truth;
  world.render(frame, image, truth);
  ASSERT_TRUE(truth.tag_fully_visible) << "frame " << frame;
  std::vector<Detection> detections = detectTag36h11(image);
  ASSERT_EQ(detections.size(), 1u) << "frame " << frame;
  EXPECT_EQ(detections[0].id, world.scene().rig.tag_id);
  auto corners_w = tagCornersWorld(world.scene().rig.tag_size_m);
  auto expected = projectWorldPoints(world.scene().camera, truth.pose, {corners_w.begin(), corners_w.end()});
  for (int c = 0; c < 4; ++c) {
    // libapriltag puts pixel centres at (0.5, 0.5) where OpenCV (and this
    // simulator) put them at (0, 0) (AprilRobotics/apriltag#121): shift first.
    const glm::dvec2 detected = detections[0].corners_px[c] - glm::dvec2(kApriltagPixelCentre);
    // It fits straight lines to the border edges; on an antialiased, noisy
    // (sigma 1.5 codes) render its corners are good to ~0.2 px, and the mild
    // lens distortion bends a 100-200 px edge by up to ~0.3 px (measured worst
    // 0.42 px). A wrong orientation or mirror would be off by a whole tag edge
    // (>= 40 px) or fail to decode at all.
    EXPECT_NEAR(detected.x, expected[c].x, 0.6) << "frame " << frame << " corner " << c;
    EXPECT_NEAR(detected.y, expected[c].y, 0.6) << "frame " << frame << " corner " << c;
  }
}

TEST(TagConventions, DetectorCornersMatchProjectedWorldCornersOnDefaultPath) {
  World world(defaultScene());
  expectCornersMatch(world, 0);
  expectCornersMatch(world, 450);  // 90 deg further round the orbit
}

TEST(TagConventions, DetectorCornersMatchOnGrazingAndFrontoParallelViews) {
  SceneConfig scene = defaultScene();
  scene.camera_path.name = "random";
  World world(scene);
  // Random pose kinds cycle: index % 3 == 0 grazing, 1 fronto-parallel, 2 between.
  for (std::uint64_t frame : {0u, 1u, 2u, 3u, 4u}) expectCornersMatch(world, frame);
}

TEST(TagConventions, WorldAxesPointAtPrintedImageRightAndTopEdges) {
  // From the default view (camera on -Y, looking +Y, tilted down) the printed
  // tag is upright: +X goes right in the image and +Y goes up (smaller row).
  World world(defaultScene());
  FrameTruth truth = world.truth(0);
  auto p = projectWorldPoints(world.scene().camera, truth.pose, {{0, 0, 0}, {0.05, 0, 0}, {0, 0.05, 0}});
  EXPECT_GT(p[1].x - p[0].x, 20.0);
  EXPECT_LT(p[2].y - p[0].y, -10.0);
}

// The printed image covers exactly [-h, h)^2 (h = printedHalfSizeM()): the
// quick rejection in front of the cell lookup must not move its edges. Points
// a nanometre inside each edge are on the tag, a nanometre outside are off,
// and so are points far away and NaN.
TEST(TagConventions, ThePrintedImageEndsExactlyAtItsEdges) {
  const TagPattern tag("tag36h11", 0, 0.08);
  const double h = tag.printedHalfSizeM();
  EXPECT_NEAR(h, 0.08 * tag.totalCells() / tag.borderCells() / 2.0, 1e-15);
  constexpr double kNanometre = 1e-9;
  bool white = false;
  for (const double along : {-h + kNanometre, 0.0, h - kNanometre}) {
    EXPECT_TRUE(tag.sample(-h + kNanometre, along, white)) << along;
    EXPECT_TRUE(tag.sample(h - kNanometre, along, white)) << along;
    EXPECT_TRUE(tag.sample(along, -h + kNanometre, white)) << along;
    EXPECT_TRUE(tag.sample(along, h - kNanometre, white)) << along;
    EXPECT_FALSE(tag.sample(-h - kNanometre, along, white)) << along;
    EXPECT_FALSE(tag.sample(h + kNanometre, along, white)) << along;
    EXPECT_FALSE(tag.sample(along, -h - kNanometre, white)) << along;
    EXPECT_FALSE(tag.sample(along, h + kNanometre, white)) << along;
  }
  // The outer ring is white (libapriltag's images have a white quiet zone)
  // and the border inside it black.
  const double cell = 2.0 * h / tag.totalCells();
  ASSERT_TRUE(tag.sample(-h + 0.5 * cell, 0.0, white));
  EXPECT_TRUE(white);
  ASSERT_TRUE(tag.sample(-h + 1.5 * cell, 0.0, white));
  EXPECT_FALSE(white);
  EXPECT_FALSE(tag.sample(1e6, -1e6, white));
  EXPECT_FALSE(tag.sample(std::nan(""), 0.0, white));
}

}  // namespace
}  // namespace probelight::sim
