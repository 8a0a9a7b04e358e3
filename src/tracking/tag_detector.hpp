// AprilTag detection on a luma plane, with corners converted to probelight's
// conventions (world-corner order, OpenCV pixel centres).
#pragma once

#include "core/apriltag_families.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

struct apriltag_detector;
struct apriltag_family;

namespace probelight::tracking {

// Defaults chosen by measurement at 640x480 on the desktop (x86, 2 shared
// cores; build/probelight_bench --benchmark_filter=detect_pose, one thread,
// docs/benchmarks.md): detection + refined pose on a whole frame takes 23 ms
// at quad_decimate 1, 6.5 ms at 2, 4.3 ms at 3; following the tag in a
// window (track_in_window) 4.6, 2.6 and 2.3 ms. At 2 with refine_edges, rendered tags
// down to 25 px across are found with corners within 0.3 px for >= 32 px;
// at 3, 25 px tags are lost, and without refine_edges the corners are off by
// up to 1.8 px. The kiosk's tag is 60-200 px across, so 2 leaves margin for
// steep views and a slower Pi; 3 is the next step if the CPU is short.
// The most worker threads libapriltag may be given without crashing: 1 with
// the libapriltag of Debian bookworm (3.3.0), whose worker pool hands out
// tasks while the array holding them is still growing
// (AprilRobotics/apriltag#339, fixed in 3.4.3). Measured here: creating a
// detector and detecting with 2 threads crashed within 3,000 tries in 6 of
// 6 runs, with 1 thread never. More threads made detection no faster on the
// desktop anyway (docs/benchmarks.md).
int maxDetectorThreads();
// The libapriltag version this build was compiled against, for messages.
const char* aprilTagVersion();

struct TagDetectorSettings {
  std::string family = "tag36h11";
  float quad_decimate = 2.0f;      // quads are found on an image this many times smaller
  int nthreads = 1;                // at most maxDetectorThreads(); capture and rendering use the other cores
  float quad_sigma = 0.0f;         // Gaussian blur (px) before quad search; >0 for noisy sensors
  bool refine_edges = true;        // snap decimated edges to full-resolution gradients
  double decode_sharpening = 0.25; // libapriltag's default
  // When the two planar-pose solutions' reprojection errors differ by less
  // than this, the corners cannot tell them apart (detection noise is a few
  // tenths of a pixel) and the one nearer the previous frame's pose wins.
  double pose_ambiguity_margin_px = 0.5;
  // Re-fit each tag edge at full resolution in linear light and intersect the
  // lines (corner_refiner.hpp), then polish the pose on every edge point of
  // the tag, bit cells included: removes the sRGB edge bias of refine_edges
  // (-0.17 px, the dark quad shrunk) and pins near fronto-parallel tilts.
  // Costs ~2 ms a frame on the desktop; tests/tracking/pose_accuracy_test.cpp
  // measures both settings.
  bool refine_corners = true;
  // With refine_corners: a frame whose detector corners are each within
  // this of those of the last refined frame keeps that frame's refinement
  // and polished pose, at most refinement_reuse_frames frames in a row
  // (tracking/refinement_reuse.hpp). 0 refines every frame.
  double refinement_reuse_px = 0.1;
  int refinement_reuse_frames = 30;
  // While the tag is tracked from frame to frame, look for it only in a
  // window around where its motion predicts it (the printed tag plus a
  // margin), which costs in proportion to the window's area; the whole
  // frame is searched when the window misses, when the tag was lost, and
  // every full_frame_every_frames frames so that a second copy of the tag
  // or other tags entering the view are still reported.
  bool track_in_window = true;
  int full_frame_every_frames = 30;
};

// AprilTag reports pixel coordinates with pixel i spanning [i, i+1), so its
// centre is at i + 0.5; OpenCV (and probelight) put the centre at i. Measured:
// an axis-aligned tag whose border starts at pixel column 120 is reported at
// x = 120.0. probelight coordinate = AprilTag coordinate - kAprilTagPixelOffsetPx.
inline constexpr double kAprilTagPixelOffsetPx = 0.5;

// libapriltag's corner order p[0..3], relative to the printed tag image
// (apriltag_to_image, row 0 at its top): bottom-left, bottom-right, top-right,
// top-left. That is exactly probelight's world order, corner k = image of
// (-s/2,-s/2,0), (+s/2,-s/2,0), (+s/2,+s/2,0), (-s/2,+s/2,0): the two orders
// coincide, which tests/tracking checks on rendered and real images.
inline constexpr std::array<int, 4> kWorldCornerFromAprilTagCorner{0, 1, 2, 3};

struct TagDetection {
  int id = -1;
  int hamming = 0;               // bits corrected while decoding
  double decision_margin = 0.0;  // mean |bit intensity - threshold|; low = doubtful decode
  // Corner k is the image of world corner k (see kWorldCornerFromAprilTagCorner),
  // OpenCV pixel convention, distorted (as seen in the frame).
  std::array<glm::dvec2, 4> corners_px{};
  glm::dvec2 center_px{0.0};
};

namespace detail {
struct DetectorDeleter {
  void operator()(apriltag_detector* detector) const;
};
}  // namespace detail

// Owns a libapriltag detector and its family. Not copyable; one thread at a
// time (the detector keeps its own worker pool of `nthreads`).
class TagDetector {
 public:
  // Throws std::invalid_argument for an unknown family or bad settings.
  explicit TagDetector(const TagDetectorSettings& settings);
  ~TagDetector();
  TagDetector(const TagDetector&) = delete;
  TagDetector& operator=(const TagDetector&) = delete;
  TagDetector(TagDetector&&) noexcept;
  TagDetector& operator=(TagDetector&&) noexcept;

  // Detects every tag of the family on an 8-bit luma plane, read in place
  // (no copy) with its row stride. A frame too small to hold a tag, or a null
  // plane, gives no detections. Never throws.
  std::vector<TagDetection> detect(const std::uint8_t* luma, int width, int height, int stride_bytes);

  const TagDetectorSettings& settings() const { return settings_; }
  // Smallest width and height detect() looks at: libapriltag crashes on
  // images that decimate to a pixel or two.
  int minimumFrameSizePx() const;
  // The family's width_at_border: the detected quad's side in bit cells.
  int borderWidthCells() const;
  // The family's total_width: the printed image's side in cells, white ring included.
  int totalWidthCells() const;

 private:
  TagDetectorSettings settings_;
  // Declared first so it is destroyed last: the detector borrows the family.
  AprilTagFamilyHandle family_;
  std::unique_ptr<apriltag_detector, detail::DetectorDeleter> detector_;
};

// Names libapriltag can create (tag36h11, tag25h9, tag16h5, tagStandard41h12, ...).
std::vector<std::string> availableTagFamilies();

}  // namespace probelight::tracking
