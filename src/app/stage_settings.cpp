#include "app/stage_settings.hpp"

namespace probelight {

tracking::TagDetectorSettings tagDetectorSettings(const AppSettings& settings, const RigGeometry& rig) {
  tracking::TagDetectorSettings detector;
  detector.family = rig.tag_family;
  detector.quad_decimate = static_cast<float>(settings.tracking.quad_decimate);
  detector.nthreads = settings.tracking.threads;
  detector.quad_sigma = static_cast<float>(settings.tracking.quad_sigma);
  detector.refine_edges = settings.tracking.refine_edges;
  return detector;
}

pipeline::EnvironmentMapSettings environmentMapSettings(const AppSettings& settings) {
  return settings.maps.stages;
}

}  // namespace probelight
