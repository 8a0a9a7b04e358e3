#include "stages/truth_monitor.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"

namespace probelight {

TruthMonitor::TruthMonitor(std::shared_ptr<const sim::World> world, RunReport& report)
    : world_(std::move(world)), report_(report) {}

void TruthMonitor::observe(const FrameContext& ctx, const MapsStage& maps, const ibl::SceneLighting& lighting) {
  if (!ctx.frame.metadata.truth) return;
  const FrameTruth& truth = *ctx.frame.metadata.truth;
  if (truth.probe_radius_px > 0.0) {
    if (previous_truth_center_px_)
      truth_center_shift_px_.add(glm::length(truth.probe_center_px - *previous_truth_center_px_));
    previous_truth_center_px_ = truth.probe_center_px;
  } else {
    previous_truth_center_px_.reset();
  }
  measureTracking(truth, ctx);
  // Whatever the maps hold now, updated this frame or kept, against the
  // truth now: a map kept too long (a lamp switched on) shows here.
  if (world_ && maps.haveMaps() && maps.mapsView() && ctx.number % kCheckEveryFrames == 0) {
    const MapErrors errors = measureMaps(ctx.frame.metadata.sequence, *maps.mapsView(), maps.maps(), lighting);
    truth_checks_.push_back({{"frame", ctx.number},
                             {"diffuse_irradiance_rel_error_vs_clipped", finiteOrNull(errors.diffuse_vs_clipped)},
                             {"lit_irradiance_rel_error_vs_hdr", finiteOrNull(errors.lit_vs_hdr)},
                             {"frames_since_map_update", maps.framesSinceUpdate()}});
  }
}

void TruthMonitor::measureTracking(const FrameTruth& truth, const FrameContext& ctx) {
  const tracking::TagTrackResult& track = ctx.track;
  if (!track.found) return;
  if (ctx.unsmoothed_view) {
    report_.recordAccuracy("pose_rotation_error_deg_unsmoothed",
                           rotationAngleDeg(ctx.unsmoothed_view->pose.R_cam_from_world, truth.pose.R_cam_from_world));
    const ibl::ProbeOutline raw_outline = ibl::computeProbeOutline(*ctx.unsmoothed_view);
    if (raw_outline.valid && truth.probe_radius_px > 0.0)
      report_.recordAccuracy("probe_center_error_px_unsmoothed",
                             glm::length(raw_outline.center_px - truth.probe_center_px));
  }
  report_.recordAccuracy("pose_rotation_error_deg",
                         rotationAngleDeg(track.pose.R_cam_from_world, truth.pose.R_cam_from_world));
  const double distance = glm::length(truth.pose.t_cam_from_world);
  report_.recordAccuracy("pose_translation_error_pct",
                         100.0 * glm::length(track.pose.t_cam_from_world - truth.pose.t_cam_from_world) / distance);
  const ibl::ProbeOutline& outline = ctx.outline;
  if (outline.valid && truth.probe_radius_px > 0.0) {
    report_.recordAccuracy("probe_center_error_px", glm::length(outline.center_px - truth.probe_center_px));
    report_.recordAccuracy("probe_radius_error_px", std::abs(outline.radius_px - truth.probe_radius_px));
  }
}

// The GPU's maps against the simulator's radiance and irradiance, for the
// view the maps were made from.
TruthMonitor::MapErrors TruthMonitor::measureMaps(std::uint64_t frame_index, const ibl::MirrorBallView& view,
                                                  const passes::EnvironmentMaps& maps,
                                                  const ibl::SceneLighting& lighting) {
  using ibl::luminance;
  // Reflection map, over the directions the ball shows well: within 100
  // degrees of the direction back toward the camera (beyond that the view is
  // squeezed into the rim, and behind it is the blind spot). Only the sky
  // (z > 0) is compared: the environment there is distant, while the floor
  // below is so close to the ball that what its surface reflects differs from
  // the truth seen from its centre (parallax), which no environment map holds.
  std::string error;
  const std::optional<ibl::CubeMapRGB> reflection_read = maps.readReflection(error);
  const std::optional<ibl::CubeMapRGB> diffuse_read = maps.readDiffuse(error);
  if (!reflection_read || !diffuse_read) return {};
  const ibl::CubeMapRGB& reflection = *reflection_read;
  const glm::dvec3 to_camera = glm::normalize(view.pose.cameraCenterWorld() - view.center_w);
  const double rim_cosine = std::cos(glm::radians(100.0));
  double abs_error_sum = 0.0;
  double truth_sum = 0.0;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < reflection.face_size; y += 2) {
      for (int x = 0; x < reflection.face_size; x += 2) {
        const glm::dvec3 direction = ibl::cubeTexelCenterDirection(face, x, y, reflection.face_size);
        if (direction.z <= 0.0 || glm::dot(direction, to_camera) < rim_cosine) continue;
        const glm::dvec3 truth = world_->radiance(direction, frame_index).clipped;
        abs_error_sum += std::abs(luminance(glm::dvec3(reflection.texel(face, x, y))) - luminance(truth));
        truth_sum += luminance(truth);
      }
    }
  }
  if (truth_sum > 0.0) report_.recordAccuracy("reflection_map_sky_rel_error", abs_error_sum / truth_sum);

  // Diffuse map: it stores a cosine-like average radiance, so irradiance is pi
  // times it. Compared on the up normal and the four horizontal ones.
  const ibl::CubeMapRGB& diffuse = *diffuse_read;
  const glm::dvec3 normals[] = {{0, 0, 1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  double clipped_error_sum = 0.0, lit_error_sum = 0.0;
  int clipped_errors = 0, lit_errors = 0;
  for (const glm::dvec3& normal : normals) {
    const sim::IrradianceTruth truth = world_->irradiance(normal, frame_index);
    const double estimated = std::numbers::pi * luminance(glm::dvec3(diffuse.sampleBilinear(normal)));
    if (luminance(truth.clipped) > 0.0) {
      const double relative = std::abs(estimated - luminance(truth.clipped)) / luminance(truth.clipped);
      report_.recordAccuracy("diffuse_irradiance_rel_error_vs_clipped", relative);
      clipped_error_sum += relative;
      ++clipped_errors;
    }
    if (luminance(truth.hdr) > 0.0) {
      report_.recordAccuracy("diffuse_irradiance_rel_error_vs_hdr",
                             std::abs(estimated - luminance(truth.hdr)) / luminance(truth.hdr));
      // The shaders' sum: E / pi of the map plus each clipped light's
      // clipped_diffuse_rgb * max(0, n . d).
      glm::dvec3 lit = glm::dvec3(diffuse.sampleBilinear(normal));
      for (std::size_t k = 0; k < lighting.clipped_direction_w.size(); ++k)
        lit += glm::dvec3(lighting.clipped_diffuse_rgb[k]) *
               std::max(0.0, glm::dot(normal, glm::dvec3(lighting.clipped_direction_w[k])));
      const double relative = std::abs(std::numbers::pi * luminance(lit) - luminance(truth.hdr)) / luminance(truth.hdr);
      report_.recordAccuracy("lit_irradiance_rel_error_vs_hdr", relative);
      lit_error_sum += relative;
      ++lit_errors;
    }
  }
  MapErrors errors;
  if (clipped_errors > 0) errors.diffuse_vs_clipped = clipped_error_sum / clipped_errors;
  if (lit_errors > 0) errors.lit_vs_hdr = lit_error_sum / lit_errors;
  return errors;
}

void TruthMonitor::writeReport(nlohmann::json& report) const {
  nlohmann::json& map_updates = report["map_updates"];
  recordSeries(map_updates["measured"], "truth_center_shift_px", truth_center_shift_px_);
  if (!truth_checks_.empty()) map_updates["truth_checks"] = truth_checks_;
}

}  // namespace probelight
