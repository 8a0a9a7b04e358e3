// Marker tracking: find the rig's AprilTag in a luma frame and recover the
// camera pose relative to the tag's world frame W.
//
// W: origin at the tag centre, +X toward the right edge of the printed tag
// image, +Y toward its top edge, +Z up out of the ground (right-handed, so
// the camera looking down at the tag sees +Z pointing at it).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <utility>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "tracking/refinement_reuse.hpp"
#include "tracking/tag_detector.hpp"

namespace probelight::tracking {

// World corner k of a tag of edge `tag_size_m`:
// (-s/2,-s/2,0), (+s/2,-s/2,0), (+s/2,+s/2,0), (-s/2,+s/2,0) for k = 0..3
// (bottom-left, bottom-right, top-right, top-left of the printed image).
std::array<glm::dvec3, 4> tagCornersWorld(double tag_size_m);

struct TagPoseSolution {
  PoseCamFromWorld pose;
  double reprojection_error_px = 0.0;  // RMS corner distance, through the real (distorted) camera
};

// Both solutions of the planar (IPPE square) pose problem, best first (one
// or two entries; none when OpenCV fails or every solution puts the tag
// behind the camera). `corners_px`: corner k is the image of world corner k,
// distorted pixels. Never throws.
std::vector<TagPoseSolution> solveTagPoses(const std::array<glm::dvec2, 4>& corners_px, double tag_size_m,
                                           const CameraIntrinsics& camera);

// Angle (degrees) of the rotation taking one camera orientation to the other.
inline double rotationDifferenceDeg(const glm::dmat3& a, const glm::dmat3& b) { return rotationAngleDeg(a, b); }

struct PoseChoice {
  std::size_t index = 0;   // into the solutions, best first
  bool ambiguous = false;  // errors within the margin: decided by history
};

// Resolves the planar flip ambiguity over time. Near fronto-parallel views
// the two IPPE solutions mirror the tag normal about the line of sight and
// fit noisy corners about equally well. The lowest reprojection error wins
// unless the other solution is within `ambiguity_margin_px`; then the one
// whose tag normal (in the camera frame) is nearer a smoothed history of
// chosen normals wins. Smoothing matters: a single previous pose is itself
// off by about as much as the two solutions differ from the truth.
class PoseFlipResolver {
 public:
  explicit PoseFlipResolver(double ambiguity_margin_px = 0.5) : margin_px_(ambiguity_margin_px) {}
  // `solutions_best_first` as solveTagPoses returns them; records the choice.
  PoseChoice choose(const std::vector<TagPoseSolution>& solutions_best_first);
  void reset() { reference_normal_cam_.reset(); }
  // The tag's normal (camera frame) from a pose chosen elsewhere.
  void seed(const glm::dvec3& tag_normal_cam) { reference_normal_cam_ = tag_normal_cam; }

 private:
  double margin_px_;
  std::optional<glm::dvec3> reference_normal_cam_;
};

enum class TagTrackStatus {
  kFound,
  kNoTag,            // no tag of the family in view
  kWrongId,          // tags of the family, none with the rig's id
  kSeveralTags,      // more than one tag with the rig's id: which is the rig's cannot be told
  kCutByFrameEdge,   // none found, and the last pose puts part of the printed tag outside the frame
  kPoseFailed,       // found, but no planar pose fits its corners
  kBadFrame,         // null, too small or inconsistent frame
};
// "found", "no_tag", "wrong_id", "several_tags", "cut_by_frame_edge",
// "pose_failed", "bad_frame": for report.json and analysis.json.
const char* toString(TagTrackStatus status);

struct TagTrackResult {
  bool found = false;
  TagTrackStatus status_code = TagTrackStatus::kNoTag;
  std::string status;  // one line for the user: why not found, or what was found
  int id = -1;
  // Every tag of the family in view, the rig's included (ascending ids).
  std::vector<int> ids_in_view;
  // Corner k is the image of world corner k (tagCornersWorld), OpenCV pixel
  // convention (pixel centres at integers), distorted as in the frame.
  std::array<glm::dvec2, 4> corners_px{};
  double decision_margin = 0.0;
  int hamming = 0;
  PoseCamFromWorld pose;
  double reprojection_error_px = 0.0;  // of `pose`
  // Of the other planar solution; +inf when there is only one: IPPE gave
  // one, or (refine_corners) both converged to the same pose when polished on
  // the tag's bit-cell edges, which then settle the planar ambiguity.
  double alternative_reprojection_error_px = 0.0;
  std::optional<PoseCamFromWorld> alternative_pose;
  // The two solutions were within the ambiguity margin, so the choice was
  // made by nearness to the previous frame's pose (or by error alone on a
  // first frame).
  bool pose_ambiguous = false;
  // The tag had not moved since a recent frame (RefinementReuse): its
  // corner refinement and pose polish were kept, not redone.
  bool refinement_reused = false;
};

// Detector + pose + temporal consistency for one rig. Not thread-safe: call
// track() from one thread.
class TagTracker {
 public:
  // Throws std::invalid_argument for bad settings or when the rig's family
  // differs from the detector settings' family (the rig wins: pass
  // settings.family = rig.tag_family).
  TagTracker(TagDetectorSettings settings, RigGeometry rig, CameraIntrinsics camera);

  // `luma`: 8-bit plane, `stride_bytes` per row, read in place. Never throws;
  // an empty, tiny, black or white frame gives found = false.
  TagTrackResult track(const std::uint8_t* luma, int width, int height, int stride_bytes);

  // Starts from a pose found in this frame by another tracker (the kiosk's,
  // for the frames of a bracket taken right after it): the next track()
  // searches the window around it, as after a frame of its own that found
  // the tag, and settles a planar ambiguity toward it, without a search of
  // the whole frame.
  void seed(const PoseCamFromWorld& pose);

  // Forget the pose history (e.g. after the camera was moved by hand).
  void resetHistory();

  const RigGeometry& rig() const { return rig_; }
  const CameraIntrinsics& camera() const { return camera_; }
  TagDetector& detector() { return detector_; }

 private:
  TagDetector detector_;
  RigGeometry rig_;
  CameraIntrinsics camera_;
  PoseFlipResolver flip_resolver_;
  // The last refinement and polish, kept while the tag stays still.
  struct RefinedTagPose {
    std::array<glm::dvec2, 4> corners_px{};
    std::vector<TagPoseSolution> solutions;  // polished, best first
  };
  RefinementReuse<RefinedTagPose> refinement_reuse_;
  // Where the printed tag (white ring included) was when last found, how
  // fast its corners moved then (px per frame), and how many frames ago: to
  // tell a tag that is leaving the frame from one that is simply absent.
  std::optional<std::array<glm::dvec2, 4>> last_printed_corners_px_;
  std::array<glm::dvec2, 4> printed_corner_velocity_px_{};
  int frames_since_found_ = 0;
  int frames_since_full_search_ = 0;
  // Detections in the predicted window, or the whole frame (see
  // TagDetectorSettings::track_in_window); sets searched_window_.
  std::vector<TagDetection> detectAround(const std::uint8_t* luma, int width, int height, int stride_bytes);

 public:
  // Whether the last track() searched only a window of the frame (for tests and the bench).
  bool lastSearchWasWindowed() const { return searched_window_; }

 private:
  bool searched_window_ = false;
};

// How recent the last pose must be (frames) for a lost tag to be called cut
// by the frame edge: half a second at 30 fps, before the camera can have
// moved far.
inline constexpr int kCutByEdgeMemoryFrames = 15;

}  // namespace probelight::tracking
