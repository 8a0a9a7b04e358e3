#include "tracking/pose_smoother.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include <glm/gtc/quaternion.hpp>

#include "tracking/tag_tracker.hpp"

namespace probelight::tracking {

std::vector<glm::dvec3> smoothingReferencePoints(const RigGeometry& rig) {
  std::vector<glm::dvec3> points;
  for (const glm::dvec3& corner : tagCornersWorld(rig.tag_size_m)) points.push_back(corner);
  points.push_back(rig.probe_center_w);
  return points;
}

double lowPassWeight(double cutoff_hz, double dt_s) {
  const double tau_s = 1.0 / (2.0 * std::numbers::pi * cutoff_hz);
  return 1.0 / (1.0 + tau_s / dt_s);
}

PoseSmoother::PoseSmoother(PoseSmoothingSettings settings, CameraIntrinsics camera,
                           std::vector<glm::dvec3> reference_points_w)
    : settings_(settings), camera_(camera), reference_points_w_(std::move(reference_points_w)) {
  auto positive = [](double value, const char* name) {
    if (!(value > 0.0) || !std::isfinite(value))
      throw std::invalid_argument(std::string("pose smoothing ") + name + " must be a positive number");
  };
  positive(settings_.static_cutoff_hz, "static_cutoff_hz");
  positive(settings_.max_lag_px, "max_lag_px");
  positive(settings_.speed_cutoff_hz, "speed_cutoff_hz");
  positive(settings_.reset_jump_px, "reset_jump_px");
  if (reference_points_w_.empty()) throw std::invalid_argument("pose smoothing needs at least one reference point");
}

std::vector<glm::dvec2> PoseSmoother::imageDisplacementsPx(const PoseCamFromWorld& a, const PoseCamFromWorld& b) const {
  std::vector<glm::dvec2> displacements;
  displacements.reserve(reference_points_w_.size());
  for (const glm::dvec3& p : reference_points_w_) {
    glm::dvec3 pa = a.toCamera(p), pb = b.toCamera(p);
    if (!(pa.z > 0.0) || !(pb.z > 0.0)) {
      displacements.emplace_back(0.0);
      continue;
    }
    displacements.emplace_back(camera_.fx_px * (pb.x / pb.z - pa.x / pa.z), camera_.fy_px * (pb.y / pb.z - pa.y / pa.z));
  }
  return displacements;
}

double PoseSmoother::largestDisplacementPx(const PoseCamFromWorld& a, const PoseCamFromWorld& b) const {
  double largest = 0.0;
  for (const glm::dvec2& d : imageDisplacementsPx(a, b)) largest = std::max(largest, glm::length(d));
  return largest;
}

PoseCamFromWorld PoseSmoother::update(const PoseCamFromWorld& raw, double timestamp_s) {
  bool finite = std::isfinite(timestamp_s);
  for (int i = 0; i < 3; ++i) {
    finite = finite && std::isfinite(raw.t_cam_from_world[i]);
    for (int j = 0; j < 3; ++j) finite = finite && std::isfinite(raw.R_cam_from_world[i][j]);
  }
  if (!finite) {  // passed through, and forgotten: what follows restarts cleanly
    state_.reset();
    last_cutoff_hz_ = std::numeric_limits<double>::infinity();
    return raw;
  }
  const double dt_s = state_ ? timestamp_s - state_->timestamp_s : 0.0;
  // Velocity from raw to raw: the true speed. (One Euro's reference code
  // takes raw minus the last output, which at a steady speed v reads
  // v (1 + tau / dt) and opens the filter further than the lag bound needs.)
  const std::vector<glm::dvec2> step_px = state_ ? imageDisplacementsPx(state_->raw_pose, raw)
                                                 : std::vector<glm::dvec2>(reference_points_w_.size(), glm::dvec2(0.0));
  double jump_px = 0.0;
  for (const glm::dvec2& d : step_px) jump_px = std::max(jump_px, glm::length(d));
  if (!settings_.enabled || !state_ || !(dt_s > 0.0) || dt_s > 1.0 || !(jump_px <= settings_.reset_jump_px)) {
    state_ = State{raw, raw, timestamp_s, std::vector<glm::dvec2>(reference_points_w_.size(), glm::dvec2(0.0)), 0.0};
    last_cutoff_hz_ = std::numeric_limits<double>::infinity();
    return raw;
  }
  // The One Euro filter: the low-passed velocity sets the cutoff for the pose itself.
  const double speed_weight = lowPassWeight(settings_.speed_cutoff_hz, dt_s);
  std::vector<glm::dvec2> velocity = state_->velocity_px_per_s;
  double speed = 0.0;
  for (std::size_t i = 0; i < velocity.size(); ++i) {
    velocity[i] += speed_weight * (step_px[i] / dt_s - velocity[i]);
    speed = std::max(speed, glm::length(velocity[i]));
  }
  const double beta_per_px = 1.0 / (2.0 * std::numbers::pi * settings_.max_lag_px);
  last_cutoff_hz_ = settings_.static_cutoff_hz + beta_per_px * speed;
  const double weight = lowPassWeight(last_cutoff_hz_, dt_s);

  // Rotation along the geodesic (slerp), translation linearly: both by the
  // same weight, so the smoothed pose lies between the last one and the raw.
  const glm::dquat previous = glm::quat_cast(state_->pose.R_cam_from_world);
  glm::dquat target = glm::quat_cast(raw.R_cam_from_world);
  if (glm::dot(previous, target) < 0.0) target = -target;  // the short way round
  PoseCamFromWorld smoothed;
  smoothed.R_cam_from_world = glm::mat3_cast(glm::normalize(glm::slerp(previous, target, weight)));
  smoothed.t_cam_from_world = state_->pose.t_cam_from_world + weight * (raw.t_cam_from_world - state_->pose.t_cam_from_world);
  state_ = State{smoothed, raw, timestamp_s, std::move(velocity), speed};
  return smoothed;
}

}  // namespace probelight::tracking
