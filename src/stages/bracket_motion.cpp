#include "stages/bracket_motion.hpp"

#include <cmath>

#include <glm/gtc/quaternion.hpp>

namespace probelight {

namespace {

glm::dvec3 rotationVector(const glm::dmat3& rotation) {
  const glm::dquat q = glm::normalize(glm::quat_cast(rotation));
  // The shorter way round: q and -q are the same rotation.
  const glm::dquat shortest = q.w < 0.0 ? -q : q;
  const double sin_half = glm::length(glm::dvec3(shortest.x, shortest.y, shortest.z));
  if (sin_half < 1e-12) return glm::dvec3(2.0 * shortest.x, 2.0 * shortest.y, 2.0 * shortest.z);
  const double angle = 2.0 * std::atan2(sin_half, shortest.w);
  return glm::dvec3(shortest.x, shortest.y, shortest.z) * (angle / sin_half);
}

glm::dmat3 rotationFromVector(const glm::dvec3& v) {
  const double angle = glm::length(v);
  if (angle < 1e-15) return glm::dmat3(1.0);
  return glm::mat3_cast(glm::angleAxis(angle, v / angle));
}

}  // namespace

BracketMotion::BracketMotion(const PoseCamFromWorld& reference, double reference_time_s)
    : reference_(reference), reference_time_s_(reference_time_s) {}

void BracketMotion::addTracked(double time_s, const PoseCamFromWorld& pose) {
  const double dt = time_s - reference_time_s_;
  if (!std::isfinite(dt) || dt == 0.0) return;
  samples_.push_back({dt, rotationVector(pose.R_cam_from_world * glm::transpose(reference_.R_cam_from_world)),
                      pose.cameraCenterWorld() - reference_.cameraCenterWorld()});
}

std::optional<PoseCamFromWorld> BracketMotion::poseAt(double time_s) const {
  const double dt = time_s - reference_time_s_;
  if (samples_.empty() || !std::isfinite(dt)) return std::nullopt;
  // Least squares through the origin: v = sum(dt d) / sum(dt^2).
  double dt_sq = 0.0;
  glm::dvec3 rotation_rate(0.0), centre_rate(0.0);
  for (const Sample& s : samples_) {
    dt_sq += s.dt_s * s.dt_s;
    rotation_rate += s.dt_s * s.rotation_vector;
    centre_rate += s.dt_s * s.centre_shift_w;
  }
  rotation_rate /= dt_sq;
  centre_rate /= dt_sq;
  PoseCamFromWorld pose;
  pose.R_cam_from_world = rotationFromVector(rotation_rate * dt) * reference_.R_cam_from_world;
  const glm::dvec3 centre = reference_.cameraCenterWorld() + centre_rate * dt;
  pose.t_cam_from_world = -(pose.R_cam_from_world * centre);
  return pose;
}

}  // namespace probelight
