// AppSettings (probelight.yaml) turned into the settings of the pipeline's
// stages, in one place, so that `probelight run` and `probelight analyze`
// build the same tracker and the same maps from the same file and their
// numbers can be compared.
#pragma once

#include "app/app_settings.hpp"
#include "core/types.hpp"
#include "ibl/surface_shading.hpp"
#include "pipeline/environment_maps.hpp"
#include "pipeline/ground_shadow.hpp"
#include "tracking/tag_detector.hpp"

namespace probelight {

// The detector settings of probelight.yaml's `tracking` section, with the
// family the rig names (the tracker insists they agree).
tracking::TagDetectorSettings tagDetectorSettings(const AppSettings& settings, const RigGeometry& rig);

// The `environment_maps` section as the GPU stages take it (force_8bit is not
// here: it changes the capabilities the stages are given, not their settings).
// Glossy maps are allocated only when the object's material reads them.
pipeline::EnvironmentMapSettings environmentMapSettings(const AppSettings& settings);

// The `object` section as the shading takes it.
ibl::SurfaceMaterial objectMaterial(const AppSettings& settings);

// The `lights` section's shadow settings, with the camera's transfer (the
// composite decodes and re-encodes camera pixels).
pipeline::GroundShadowSettings groundShadowSettings(const AppSettings& settings);

}  // namespace probelight
