// probelight.yaml's stage sections (PipelineSettings) turned into the
// settings of the passes and the maths they drive, in one place, so that
// `run`, `analyze` and `render` build the same tracker, maps, shadows and
// lighting fit from the same file, and their numbers can be compared.
#pragma once

#include <optional>
#include <vector>

#include "stages/pipeline_settings.hpp"
#include "core/types.hpp"
#include "ibl/lighting_fit.hpp"
#include "ibl/sensor_noise.hpp"
#include "ibl/surface_shading.hpp"
#include "passes/environment_maps.hpp"
#include "passes/ground_shadow.hpp"
#include "tracking/tag_detector.hpp"

namespace probelight {

// The detector settings of probelight.yaml's `tracking` section, with the
// family the rig names (the tracker insists they agree).
tracking::TagDetectorSettings tagDetectorSettings(const PipelineSettings& settings, const RigGeometry& rig);

// The `environment_maps` section as the GPU stages take it (force_8bit is not
// here: it changes the capabilities the stages are given, not their settings).
// Glossy maps are allocated only when the object reads them
// (SceneObject::readsGlossy with glossyExponents: the sphere's material, or
// a model's materials, whatever the sphere's settings say).
passes::EnvironmentMapSettings environmentMapSettings(const PipelineSettings& settings, bool object_reads_glossy);

// The exponents of the glossy levels the maps are configured with (sharpest
// first), whether or not the object reads them.
std::vector<double> glossyExponents(const PipelineSettings& settings);

// The `object` section as the shading takes it.
ibl::SurfaceMaterial objectMaterial(const PipelineSettings& settings);

// The `lights` section's shadow settings, with the camera's transfer (the
// composite decodes and re-encodes camera pixels).
passes::GroundShadowSettings groundShadowSettings(const PipelineSettings& settings);

// The white ring of rig.yaml's tag (its family's border geometry at its
// size), where the lighting fit reads the light on the ground; none for a
// family libapriltag does not know (rig.yaml's reader refuses those).
std::optional<ibl::WhiteRing> tagWhiteRingOf(const RigGeometry& rig);
// The printed tag's cells, where the frame's noise is measured.
std::optional<ibl::TagCellGrid> tagCellGridOf(const RigGeometry& rig);

// The `lights` section's fit settings, with the camera's transfer (the
// border and the post are read in camera codes).
ibl::LightingFitSettings lightingFitSettings(const PipelineSettings& settings);

}  // namespace probelight
