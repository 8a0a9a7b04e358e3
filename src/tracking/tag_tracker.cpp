#include "tracking/tag_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "tracking/corner_refiner.hpp"

namespace probelight::tracking {

namespace {

cv::Matx33d cameraMatrix(const CameraIntrinsics& camera) {
  return {camera.fx_px, 0.0, camera.cx_px, 0.0, camera.fy_px, camera.cy_px, 0.0, 0.0, 1.0};
}

cv::Mat distortionVector(const CameraIntrinsics& camera) {
  cv::Mat distortion(1, 5, CV_64F);
  for (int i = 0; i < 5; ++i) distortion.at<double>(0, i) = camera.distortion[static_cast<std::size_t>(i)];
  return distortion;
}

glm::dmat3 toGlm(const cv::Matx33d& m) {
  glm::dmat3 result;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) result[col][row] = m(row, col);  // glm is column-major
  return result;
}

std::string describeIds(const std::vector<int>& ids) {
  std::string text;
  for (int id : ids) text += (text.empty() ? "" : ", ") + std::to_string(id);
  return text;
}

// The printed tag's corners (white ring included) in the frame for `pose`;
// nullopt when one lies behind the camera or OpenCV fails.
std::optional<std::array<glm::dvec2, 4>> printedCornersPx(const PoseCamFromWorld& pose, double printed_size_m,
                                                          const CameraIntrinsics& camera) {
  try {
    std::vector<cv::Point3d> camera_points;
    for (const glm::dvec3& p : tagCornersWorld(printed_size_m)) {
      glm::dvec3 c = pose.toCamera(p);
      if (!(c.z > 0.0)) return std::nullopt;
      camera_points.emplace_back(c.x, c.y, c.z);
    }
    std::vector<cv::Point2d> image;
    cv::projectPoints(camera_points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cameraMatrix(camera),
                      distortionVector(camera), image);
    std::array<glm::dvec2, 4> corners;
    for (std::size_t k = 0; k < 4; ++k) corners[k] = glm::dvec2(image[k].x, image[k].y);
    return corners;
  } catch (const cv::Exception&) {
    return std::nullopt;
  }
}

}  // namespace

namespace {

// Each IPPE solution polished by Gauss-Newton on every edge point the
// refiner found (outer edges and bit-cell boundaries): the residual is a
// point's distance to the projection of its tag segment (pinhole, points
// already undistorted). Hundreds of points at many positions and sub-pixel
// phases pin the tilt that four corners leave loose near fronto-parallel
// views. Each solution stays in its own basin (the two are separate minima),
// so the flip choice still sees both. The reported reprojection error stays
// that of the four outer corners, which the ambiguity margin is set for.
void refineOnEdgePoints(std::vector<TagPoseSolution>& solutions, const std::array<glm::dvec2, 4>& corners_px,
                        const std::vector<TagEdgePoint>& points, double tag_size_m, const CameraIntrinsics& camera) {
  if (points.size() < 12) return;
  const double start_separation_deg =
      solutions.size() == 2
          ? rotationDifferenceDeg(solutions[0].pose.R_cam_from_world, solutions[1].pose.R_cam_from_world)
          : 0.0;
  const double half = tag_size_m / 2.0;
  // Residual i: the signed distance (px, undistorted) of edge point u from
  // the line through the projections a, b of its segment's ends, r =
  // cross(u - a, e) / |e| with e = b - a. Its gradient in the 6 parameters
  // (a small rotation w applied on the left in the camera frame, then t)
  // is analytic: with s = u - a, L = |e|, n_e = (e.y, -e.x), m_s = (-s.y, s.x),
  //   dr = da . ((-n_e - m_s) / L + r e / L^2) + db . (m_s / L - r e / L^2),
  // and a point X_c = R X + t moves by -[R X]x dw + dt, projected through the
  // pinhole's Jacobian. One pass over the points gives r and J (a numerical
  // Jacobian took 7).
  auto residualsAndJacobian = [&](const glm::dmat3& R, const glm::dvec3& t, std::vector<double>& r,
                                  std::vector<std::array<double, 6>>& jacobian) {
    r.resize(points.size());
    jacobian.resize(points.size());
    struct Projected {
      glm::dvec2 pixel;
      std::array<glm::dvec2, 6> d;  // d pixel / d parameter
    };
    // The points come a segment at a time (the corner refiner lists them so),
    // so a segment's two projected ends are kept for the points after it.
    std::optional<std::pair<glm::dvec2, glm::dvec2>> last_segment;
    Projected a, b;
    for (std::size_t i = 0; i < points.size(); ++i) {
      auto project = [&](glm::dvec2 q) {
        const glm::dvec3 rotated = R * glm::dvec3(q.x * half, q.y * half, 0.0);
        const glm::dvec3 c = rotated + t;
        Projected out;
        out.pixel = glm::dvec2(camera.fx_px * c.x / c.z + camera.cx_px, camera.fy_px * c.y / c.z + camera.cy_px);
        // d pixel / d c (2 x 3), then d c / d w = -[rotated]x and d c / d t = I.
        const glm::dvec3 du(camera.fx_px / c.z, 0.0, -camera.fx_px * c.x / (c.z * c.z));
        const glm::dvec3 dv(0.0, camera.fy_px / c.z, -camera.fy_px * c.y / (c.z * c.z));
        for (int k = 0; k < 3; ++k) {
          glm::dvec3 axis(0.0);
          axis[k] = 1.0;
          const glm::dvec3 dc_dw = glm::cross(axis, rotated);  // d (w x rotated) / d w_k
          out.d[static_cast<std::size_t>(k)] = glm::dvec2(glm::dot(du, dc_dw), glm::dot(dv, dc_dw));
          out.d[static_cast<std::size_t>(k + 3)] = glm::dvec2(du[k], dv[k]);
        }
        return out;
      };
      const std::pair<glm::dvec2, glm::dvec2> segment(points[i].segment_a, points[i].segment_b);
      if (!last_segment || *last_segment != segment) {
        a = project(segment.first);
        b = project(segment.second);
        last_segment = segment;
      }
      const glm::dvec2 e = b.pixel - a.pixel, s = points[i].undistorted_px - a.pixel;
      const double length = glm::length(e);
      const double residual = (s.x * e.y - s.y * e.x) / length;
      const glm::dvec2 n_e(e.y, -e.x), m_s(-s.y, s.x);
      const glm::dvec2 ga = (-n_e - m_s) / length + residual * e / (length * length);
      const glm::dvec2 gb = m_s / length - residual * e / (length * length);
      r[i] = residual;
      for (std::size_t p = 0; p < 6; ++p) jacobian[i][p] = glm::dot(ga, a.d[p]) + glm::dot(gb, b.d[p]);
    }
  };
  auto rotationFromVector = [](const glm::dvec3& w) {
    cv::Matx33d m;
    cv::Rodrigues(cv::Vec3d(w.x, w.y, w.z), m);
    return toGlm(m);
  };
  // Huber weights at a quarter pixel: edge points are good to a few
  // hundredths of a pixel, so one farther out is a misplaced profile (a
  // cell boundary blurred into its neighbour), down-weighted, not trusted.
  constexpr double kHuberPx = 0.25;
  for (TagPoseSolution& solution : solutions) {
    glm::dmat3 R = solution.pose.R_cam_from_world;
    glm::dvec3 t = solution.pose.t_cam_from_world;
    std::vector<double> r;
    std::vector<std::array<double, 6>> jacobian;
    for (int iteration = 0; iteration < 6; ++iteration) {
      residualsAndJacobian(R, t, r, jacobian);
      cv::Matx66d JtJ = cv::Matx66d::zeros();
      cv::Vec6d Jtr = cv::Vec6d::all(0.0);
      for (std::size_t i = 0; i < r.size(); ++i) {
        const double weight = std::abs(r[i]) <= kHuberPx ? 1.0 : kHuberPx / std::abs(r[i]);
        for (int p = 0; p < 6; ++p) {
          const double wj = weight * jacobian[i][static_cast<std::size_t>(p)];
          Jtr(p) += wj * r[i];
          for (int q = p; q < 6; ++q) JtJ(p, q) += wj * jacobian[i][static_cast<std::size_t>(q)];
        }
      }
      for (int p = 0; p < 6; ++p)
        for (int q = 0; q < p; ++q) JtJ(p, q) = JtJ(q, p);
      cv::Vec6d step;
      if (!cv::solve(JtJ, -Jtr, step, cv::DECOMP_CHOLESKY)) break;
      glm::dvec3 dw(step(0), step(1), step(2));
      glm::dvec3 dt(step(3), step(4), step(5));
      R = rotationFromVector(dw) * R;
      t += dt;
      if (glm::length(dw) < 1e-9 && glm::length(dt) < 1e-9 * glm::length(t)) break;
    }
    if (!(t.z > 0.0) || !std::isfinite(t.z)) continue;
    // Reprojection error of the outer corners, in the distorted frame, as solveTagPoses reports it.
    cv::Matx33d Rcv;
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) Rcv(row, col) = R[col][row];
    cv::Vec3d rvec;
    cv::Rodrigues(Rcv, rvec);
    std::vector<cv::Point3d> world;
    for (const glm::dvec3& p : tagCornersWorld(tag_size_m)) world.emplace_back(p.x, p.y, p.z);
    std::vector<cv::Point2d> projected;
    cv::projectPoints(world, rvec, cv::Vec3d(t.x, t.y, t.z), cameraMatrix(camera), distortionVector(camera), projected);
    double squared_sum = 0.0;
    for (std::size_t k = 0; k < 4; ++k) {
      cv::Point2d d = projected[k] - cv::Point2d(corners_px[k].x, corners_px[k].y);
      squared_sum += d.dot(d);
    }
    double error = std::sqrt(squared_sum / 4.0);
    // The polished pose must still fit the outer corners about as well (the
    // edge points include them): a pixel worse means it was led astray, e.g.
    // by a pattern that is not the tag's grid; keep the four-corner pose.
    if (!std::isfinite(error) || error > solution.reprojection_error_px + 1.0) continue;
    solution.pose.R_cam_from_world = R;
    solution.pose.t_cam_from_world = t;
    solution.reprojection_error_px = error;
  }
  std::sort(solutions.begin(), solutions.end(),
            [](const TagPoseSolution& a, const TagPoseSolution& b) { return a.reprojection_error_px < b.reprojection_error_px; });
  // With the bit cells' edges the mirrored solution is often no longer a
  // minimum: both starts converge to one pose (within the Huber reweighting's
  // last step, thousandths of a degree). Ending at under a twentieth of the
  // distance they started apart means one basin: there is no ambiguity left
  // to resolve, so keep one.
  if (solutions.size() == 2 &&
      rotationDifferenceDeg(solutions[0].pose.R_cam_from_world, solutions[1].pose.R_cam_from_world) <
          0.05 * start_separation_deg)
    solutions.pop_back();
}

}  // namespace

const char* toString(TagTrackStatus status) {
  switch (status) {
    case TagTrackStatus::kFound: return "found";
    case TagTrackStatus::kNoTag: return "no_tag";
    case TagTrackStatus::kWrongId: return "wrong_id";
    case TagTrackStatus::kSeveralTags: return "several_tags";
    case TagTrackStatus::kCutByFrameEdge: return "cut_by_frame_edge";
    case TagTrackStatus::kPoseFailed: return "pose_failed";
    case TagTrackStatus::kBadFrame: return "bad_frame";
  }
  return "unknown";
}

std::array<glm::dvec3, 4> tagCornersWorld(double tag_size_m) {
  double h = tag_size_m / 2.0;
  return {glm::dvec3(-h, -h, 0.0), glm::dvec3(h, -h, 0.0), glm::dvec3(h, h, 0.0), glm::dvec3(-h, h, 0.0)};
}

std::vector<TagPoseSolution> solveTagPoses(const std::array<glm::dvec2, 4>& corners_px, double tag_size_m,
                                           const CameraIntrinsics& camera) {
  std::vector<TagPoseSolution> solutions;
  try {
    cv::Matx33d K = cameraMatrix(camera);
    cv::Mat distortion = distortionVector(camera);
    std::vector<cv::Point2d> observed_px;
    for (const glm::dvec2& corner : corners_px) observed_px.emplace_back(corner.x, corner.y);

    // Remove lens distortion first (P = K keeps pixel units), so IPPE solves
    // an exact pinhole problem. 20 iterations: the default 5 leave ~0.1 px
    // residuals near the corners of a strongly distorted (k1 = -0.27) frame.
    std::vector<cv::Point2d> undistorted_px;
    cv::undistortPoints(observed_px, undistorted_px, K, distortion, cv::noArray(), K,
                        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 1e-10));

    // SOLVEPNP_IPPE_SQUARE requires the object points in the order
    // (-s/2,+s/2), (+s/2,+s/2), (+s/2,-s/2), (-s/2,-s/2): world corners 3, 2, 1, 0.
    std::array<glm::dvec3, 4> world = tagCornersWorld(tag_size_m);
    constexpr std::array<int, 4> kWorldCornerForIppePoint{3, 2, 1, 0};
    std::vector<cv::Point3d> ippe_object;
    std::vector<cv::Point2d> ippe_image;
    for (int ippe_index : kWorldCornerForIppePoint) {
      const glm::dvec3& p = world[static_cast<std::size_t>(ippe_index)];
      ippe_object.emplace_back(p.x, p.y, p.z);
      ippe_image.push_back(undistorted_px[static_cast<std::size_t>(ippe_index)]);
    }
    std::vector<cv::Mat> rvecs, tvecs;
    cv::solvePnPGeneric(ippe_object, ippe_image, K, cv::noArray(), rvecs, tvecs, false, cv::SOLVEPNP_IPPE_SQUARE);

    std::vector<cv::Point3d> world_cv;
    for (const glm::dvec3& p : world) world_cv.emplace_back(p.x, p.y, p.z);
    for (std::size_t i = 0; i < rvecs.size(); ++i) {
      cv::Matx33d R;
      cv::Rodrigues(rvecs[i], R);
      cv::Vec3d t(tvecs[i].reshape(1, 3));
      if (!(t[2] > 0.0)) continue;  // tag behind the camera
      // Judge each solution where the corners were measured: in the distorted frame.
      std::vector<cv::Point2d> projected_px;
      cv::projectPoints(world_cv, rvecs[i], tvecs[i], K, distortion, projected_px);
      double squared_sum = 0.0;
      for (std::size_t k = 0; k < 4; ++k) {
        cv::Point2d d = projected_px[k] - observed_px[k];
        squared_sum += d.dot(d);
      }
      TagPoseSolution solution;
      solution.pose.R_cam_from_world = toGlm(R);
      solution.pose.t_cam_from_world = glm::dvec3(t[0], t[1], t[2]);
      solution.reprojection_error_px = std::sqrt(squared_sum / 4.0);
      if (std::isfinite(solution.reprojection_error_px)) solutions.push_back(solution);
    }
  } catch (const cv::Exception&) {
    solutions.clear();
  }
  std::sort(solutions.begin(), solutions.end(),
            [](const TagPoseSolution& a, const TagPoseSolution& b) { return a.reprojection_error_px < b.reprojection_error_px; });
  return solutions;
}

PoseChoice PoseFlipResolver::choose(const std::vector<TagPoseSolution>& solutions_best_first) {
  PoseChoice choice;
  if (solutions_best_first.empty()) return choice;
  auto tagNormalInCamera = [](const TagPoseSolution& solution) {
    return solution.pose.R_cam_from_world * glm::dvec3(0.0, 0.0, 1.0);
  };
  if (solutions_best_first.size() > 1) {
    const TagPoseSolution& best = solutions_best_first[0];
    const TagPoseSolution& other = solutions_best_first[1];
    choice.ambiguous = other.reprojection_error_px - best.reprojection_error_px < margin_px_;
    if (choice.ambiguous && reference_normal_cam_) {
      double best_alignment = glm::dot(tagNormalInCamera(best), *reference_normal_cam_);
      double other_alignment = glm::dot(tagNormalInCamera(other), *reference_normal_cam_);
      if (other_alignment > best_alignment) choice.index = 1;
    }
  }
  // Exponential smoothing over about 1/kSmoothing = 4 frames: averages out
  // per-frame noise while following a hand-held camera.
  constexpr double kSmoothing = 0.25;
  glm::dvec3 chosen_normal = tagNormalInCamera(solutions_best_first[choice.index]);
  reference_normal_cam_ = reference_normal_cam_
                              ? glm::normalize((1.0 - kSmoothing) * *reference_normal_cam_ + kSmoothing * chosen_normal)
                              : chosen_normal;
  return choice;
}

TagTracker::TagTracker(TagDetectorSettings settings, RigGeometry rig, CameraIntrinsics camera)
    : detector_(settings),
      rig_(std::move(rig)),
      camera_(camera),
      flip_resolver_(settings.pose_ambiguity_margin_px),
      refinement_reuse_(RefinementReuseSettings{settings.refinement_reuse_px, settings.refinement_reuse_frames}) {
  if (settings.family != rig_.tag_family)
    throw std::invalid_argument("detector family '" + settings.family + "' differs from the rig's tag_family '" +
                                rig_.tag_family + "'");
  if (!(rig_.tag_size_m > 0.0)) throw std::invalid_argument("rig tag_size must be > 0");
  if (!(settings.pose_ambiguity_margin_px >= 0.0)) throw std::invalid_argument("pose_ambiguity_margin_px must be >= 0");
  if (!(settings.refinement_reuse_px >= 0.0) || settings.refinement_reuse_frames < 0)
    throw std::invalid_argument("refinement_reuse_px and refinement_reuse_frames must be >= 0");
}

void TagTracker::resetHistory() {
  flip_resolver_.reset();
  last_printed_corners_px_.reset();
  refinement_reuse_.clear();
}

std::vector<TagDetection> TagTracker::detectAround(const std::uint8_t* luma, int width, int height, int stride_bytes) {
  searched_window_ = false;
  const TagDetectorSettings& settings = detector_.settings();
  ++frames_since_full_search_;
  // Only straight after a frame that found the tag (track() counts this
  // frame in frames_since_found_ after the search).
  if (settings.track_in_window && last_printed_corners_px_ && frames_since_found_ == 0 &&
      frames_since_full_search_ < settings.full_frame_every_frames) {
    // The printed tag where its last motion puts it, grown by a quarter of
    // its size plus that motion again (acceleration: a hand-held camera
    // changes speed by far less than its speed in one frame).
    double min_x = 1e300, min_y = 1e300, max_x = -1e300, max_y = -1e300, speed_px = 0.0;
    for (std::size_t k = 0; k < 4; ++k) {
      const glm::dvec2 predicted = (*last_printed_corners_px_)[k] + printed_corner_velocity_px_[k];
      min_x = std::min(min_x, predicted.x), max_x = std::max(max_x, predicted.x);
      min_y = std::min(min_y, predicted.y), max_y = std::max(max_y, predicted.y);
      speed_px = std::max(speed_px, glm::length(printed_corner_velocity_px_[k]));
    }
    const double margin = 0.25 * std::max(max_x - min_x, max_y - min_y) + speed_px + 8.0;
    // Origin on the whole-frame search's grid of decimated 4x4 threshold
    // tiles, so that both searches threshold the tag's pixels alike.
    const int grid = 4 * std::max(1, static_cast<int>(std::lround(settings.quad_decimate)));
    const int x0 = std::max(0, static_cast<int>(std::floor(min_x - margin)) / grid * grid);
    const int y0 = std::max(0, static_cast<int>(std::floor(min_y - margin)) / grid * grid);
    const int x1 = std::min(width, static_cast<int>(std::ceil(max_x + margin)) + 1);
    const int y1 = std::min(height, static_cast<int>(std::ceil(max_y + margin)) + 1);
    const int window_w = x1 - x0, window_h = y1 - y0;
    // Worth it only when the window is clearly smaller than the frame.
    if (window_w >= detector_.minimumFrameSizePx() && window_h >= detector_.minimumFrameSizePx() &&
        static_cast<double>(window_w) * window_h < 0.6 * static_cast<double>(width) * height) {
      std::vector<TagDetection> detections =
          detector_.detect(luma + static_cast<std::ptrdiff_t>(y0) * stride_bytes + x0, window_w, window_h, stride_bytes);
      int with_rig_id = 0;
      for (TagDetection& detection : detections) {
        for (glm::dvec2& corner : detection.corners_px) corner += glm::dvec2(x0, y0);
        detection.center_px += glm::dvec2(x0, y0);
        if (detection.id == rig_.tag_id) ++with_rig_id;
      }
      if (with_rig_id == 1) {
        searched_window_ = true;
        return detections;
      }
    }
  }
  frames_since_full_search_ = 0;
  return detector_.detect(luma, width, height, stride_bytes);
}

TagTrackResult TagTracker::track(const std::uint8_t* luma, int width, int height, int stride_bytes) {
  TagTrackResult result;
  result.alternative_reprojection_error_px = std::numeric_limits<double>::infinity();
  int minimum_px = detector_.minimumFrameSizePx();
  if (!luma || width < minimum_px || height < minimum_px || stride_bytes < width) {
    result.status_code = TagTrackStatus::kBadFrame;
    result.status = "bad frame: " + std::to_string(width) + "x" + std::to_string(height) + ", stride " +
                    std::to_string(stride_bytes) + " (need at least " + std::to_string(minimum_px) + " px each way)";
    return result;
  }

  std::vector<TagDetection> detections = detectAround(luma, width, height, stride_bytes);
  const TagDetection* chosen = nullptr;
  int with_rig_id = 0;
  for (const TagDetection& detection : detections) {
    result.ids_in_view.push_back(detection.id);
    if (detection.id == rig_.tag_id) {
      ++with_rig_id;
      chosen = &detection;
    }
  }
  std::sort(result.ids_in_view.begin(), result.ids_in_view.end());
  ++frames_since_found_;
  if (!chosen || with_rig_id > 1) refinement_reuse_.clear();
  const std::string family = rig_.tag_family;
  if (with_rig_id > 1) {
    // Two prints of the rig's tag: a pose from the wrong one would put the
    // ball's crop somewhere else entirely, so no pose at all is safer.
    result.status_code = TagTrackStatus::kSeveralTags;
    result.status = std::to_string(with_rig_id) + " " + family + " tags with the rig's id " +
                    std::to_string(rig_.tag_id) + " in view: cannot tell which is the rig's; remove the others";
    return result;
  }
  if (!chosen) {
    if (!detections.empty()) {
      result.status_code = TagTrackStatus::kWrongId;
      result.status = "wrong id: saw " + family + " id " + describeIds(result.ids_in_view) + ", the rig's tag is id " +
                      std::to_string(rig_.tag_id);
      return result;
    }
    result.status_code = TagTrackStatus::kNoTag;
    result.status = "no " + family + " tag in view";
    // libapriltag needs the whole black border and some white around it, so
    // a tag partly out of the frame is not found at all. Where it was a
    // moment ago tells that apart from a covered or absent tag.
    if (last_printed_corners_px_ && frames_since_found_ <= kCutByEdgeMemoryFrames) {
      // Where the corners would be now at the speed they last moved, and
      // whether that or the last sighting itself (within one printed cell
      // of the edge: the detector needs the white ring whole) crosses the
      // frame's edge. Some corners out: cut; all out: gone.
      const double cell_px = glm::length((*last_printed_corners_px_)[1] - (*last_printed_corners_px_)[0]) /
                             std::max(1, detector_.totalWidthCells());
      int outside = 0;
      for (std::size_t k = 0; k < 4; ++k) {
        const glm::dvec2 last = (*last_printed_corners_px_)[k];
        const glm::dvec2 now = last + static_cast<double>(frames_since_found_) * printed_corner_velocity_px_[k];
        auto out = [&](const glm::dvec2& p, double margin) {
          return p.x < -0.5 + margin || p.y < -0.5 + margin || p.x > width - 0.5 - margin ||
                 p.y > height - 0.5 - margin;
        };
        if (out(now, 0.0) || out(last, cell_px)) ++outside;
      }
      if (outside > 0 && outside < 4) {
        result.status_code = TagTrackStatus::kCutByFrameEdge;
        result.status = "tag cut by the frame edge (" + std::to_string(outside) +
                        " of its corners outside): bring the whole tag into view";
      } else if (outside == 4) {
        result.status += " (it left the frame)";
      }
    }
    return result;
  }
  result.id = chosen->id;
  result.corners_px = chosen->corners_px;
  result.decision_margin = chosen->decision_margin;
  result.hamming = chosen->hamming;
  std::vector<TagPoseSolution> solutions;
  const bool refine = detector_.settings().refine_corners;
  if (const RefinedTagPose* kept = refine ? refinement_reuse_.reuse(chosen->id, chosen->corners_px) : nullptr) {
    result.corners_px = kept->corners_px;
    solutions = kept->solutions;
    result.refinement_reused = true;
  } else {
    std::vector<TagEdgePoint> edge_points;
    if (refine) {
      // Falls back to the detector's corners when an edge cannot be re-fitted
      // (too little contrast, partly outside the frame).
      if (auto refined = refineTagCorners(luma, width, height, stride_bytes, chosen->corners_px, camera_,
                                          detector_.borderWidthCells())) {
        result.corners_px = refined->corners_px;
        edge_points = std::move(refined->edge_points);
      }
    }
    solutions = solveTagPoses(result.corners_px, rig_.tag_size_m, camera_);
    try {
      refineOnEdgePoints(solutions, result.corners_px, edge_points, rig_.tag_size_m, camera_);
    } catch (const cv::Exception&) {
      // keep the four-corner solutions
    }
    // Only a refinement that worked is worth keeping.
    if (!edge_points.empty() && !solutions.empty())
      refinement_reuse_.store(chosen->id, chosen->corners_px, RefinedTagPose{result.corners_px, solutions});
    else
      refinement_reuse_.clear();
  }
  if (solutions.empty()) {
    result.status_code = TagTrackStatus::kPoseFailed;
    result.status = "pose failed: tag " + std::to_string(chosen->id) + " found but no planar pose fits its corners";
    return result;
  }

  PoseChoice choice = flip_resolver_.choose(solutions);
  std::size_t pick = choice.index;
  result.pose_ambiguous = choice.ambiguous;
  if (solutions.size() > 1) {
    result.alternative_pose = solutions[1 - pick].pose;
    result.alternative_reprojection_error_px = solutions[1 - pick].reprojection_error_px;
  }
  result.found = true;
  result.status_code = TagTrackStatus::kFound;
  result.pose = solutions[pick].pose;
  result.reprojection_error_px = solutions[pick].reprojection_error_px;
  result.status = "tag " + std::to_string(chosen->id) + " found" + (result.pose_ambiguous ? " (pose ambiguous)" : "");
  if (detections.size() > 1) {
    std::vector<int> others;
    for (int id : result.ids_in_view)
      if (id != chosen->id) others.push_back(id);
    result.status += "; other " + family + " tags ignored: id " + describeIds(others);
  }
  // For telling a tag that leaves the frame from a missing one (above).
  if (const int border_cells = detector_.borderWidthCells(); border_cells > 0) {
    const double printed_size_m = rig_.tag_size_m * detector_.totalWidthCells() / border_cells;
    if (auto printed = printedCornersPx(result.pose, printed_size_m, camera_)) {
      for (std::size_t k = 0; k < 4; ++k)
        printed_corner_velocity_px_[k] = last_printed_corners_px_ && frames_since_found_ == 1
                                             ? (*printed)[k] - (*last_printed_corners_px_)[k]
                                             : glm::dvec2(0.0);
      last_printed_corners_px_ = printed;
    }
  }
  frames_since_found_ = 0;
  return result;
}

void TagTracker::seed(const PoseCamFromWorld& pose) {
  flip_resolver_.seed(pose.R_cam_from_world * glm::dvec3(0.0, 0.0, 1.0));
  last_printed_corners_px_.reset();
  if (const int border_cells = detector_.borderWidthCells(); border_cells > 0) {
    const double printed_size_m = rig_.tag_size_m * detector_.totalWidthCells() / border_cells;
    last_printed_corners_px_ = printedCornersPx(pose, printed_size_m, camera_);
  }
  printed_corner_velocity_px_ = {};
  frames_since_found_ = 0;
  frames_since_full_search_ = 0;
}

}  // namespace probelight::tracking
