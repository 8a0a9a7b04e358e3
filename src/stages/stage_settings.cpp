#include "stages/stage_settings.hpp"

#include "core/apriltag_families.hpp"

#include <algorithm>

namespace probelight {

tracking::TagDetectorSettings tagDetectorSettings(const PipelineSettings& settings, const RigGeometry& rig) {
  tracking::TagDetectorSettings detector;
  detector.family = rig.tag_family;
  detector.quad_decimate = static_cast<float>(settings.tracking.quad_decimate);
  detector.nthreads = settings.tracking.threads;
  detector.quad_sigma = static_cast<float>(settings.tracking.quad_sigma);
  detector.refine_edges = settings.tracking.refine_edges;
  detector.refine_corners = settings.tracking.refine_corners;
  detector.refinement_reuse_px = settings.tracking.refinement_reuse_px;
  detector.refinement_reuse_frames = settings.tracking.refinement_reuse_frames;
  detector.track_in_window = settings.tracking.track_in_window;
  detector.full_frame_every_frames = settings.tracking.full_frame_every_frames;
  return detector;
}

passes::EnvironmentMapSettings environmentMapSettings(const PipelineSettings& settings, bool object_reads_glossy) {
  passes::EnvironmentMapSettings stages = settings.maps.stages;
  if (!object_reads_glossy) stages.glossy_levels = 0;
  // A glossy level is never finer than the reflection map it filters; at a
  // smaller face_size it takes the map's own size (which divides it).
  for (int& size : stages.glossy_face_size) size = std::min(size, stages.reflection_face_size);
  return stages;
}

std::vector<double> glossyExponents(const PipelineSettings& settings) {
  const passes::EnvironmentMapSettings& maps = settings.maps.stages;
  std::vector<double> exponents;
  for (int level = 0; level < std::clamp(maps.glossy_levels, 0, 2); ++level)
    exponents.push_back(maps.glossy_exponent[static_cast<size_t>(level)]);
  return exponents;
}

ibl::SurfaceMaterial objectMaterial(const PipelineSettings& settings) {
  ibl::SurfaceMaterial material;
  material.albedo = glm::vec3(settings.object.albedo);
  material.k_specular = static_cast<float>(settings.object.k_specular);
  material.shininess = static_cast<float>(settings.object.shininess);
  material.k_reflect = static_cast<float>(settings.object.k_reflect);
  material.glossiness = static_cast<float>(settings.object.glossiness);
  return material;
}

}  // namespace probelight

namespace probelight {

passes::GroundShadowSettings groundShadowSettings(const PipelineSettings& settings) {
  passes::GroundShadowSettings shadow;
  shadow.shadow_map_size_px = settings.lights.shadow_map_size_px;
  shadow.ground_texture_size_px = settings.lights.ground_texture_size_px;
  shadow.max_region_half_size_m = settings.lights.max_shadow_reach_m;
  shadow.camera_transfer = settings.maps.stages.camera_transfer;
  return shadow;
}

}  // namespace probelight

namespace probelight {

ibl::LightingFitSettings lightingFitSettings(const PipelineSettings& settings) {
  ibl::LightingFitSettings fit;
  fit.camera_transfer = settings.maps.stages.camera_transfer;
  fit.white_reference = settings.lights.white_reference;
  fit.post_reference = settings.lights.post_reference;
  fit.dome = settings.lights.dome;
  return fit;
}

std::optional<ibl::WhiteRing> tagWhiteRingOf(const RigGeometry& rig) {
  const AprilTagFamilyHandle family = createAprilTagFamily(rig.tag_family);
  if (!family) return std::nullopt;
  return ibl::tagWhiteRing(family->width_at_border, family->reversed_border, rig.tag_size_m);
}

std::optional<ibl::TagCellGrid> tagCellGridOf(const RigGeometry& rig) {
  const AprilTagFamilyHandle family = createAprilTagFamily(rig.tag_family);
  if (!family) return std::nullopt;
  const ibl::TagCellGrid grid = ibl::tagCellGrid(family->width_at_border, family->total_width, rig.tag_size_m);
  if (grid.grid_cells <= 0) return std::nullopt;
  return grid;
}

}  // namespace probelight
