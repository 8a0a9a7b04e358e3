// rig.yaml: the physical set-up, i.e. which AprilTag is the marker, its size,
// and where the mirror ball sits in the tag's world frame W.
#pragma once

#include <string>
#include <vector>

#include "config/config_reader.hpp"
#include "core/types.hpp"

namespace probelight::config {

struct TagFamilyInfo {
  std::string name;   // as libapriltag names it, e.g. "tag36h11"
  int code_count;     // valid ids are 0 .. code_count-1
};

// The families libapriltag 3.3 ships.
const std::vector<TagFamilyInfo>& knownTagFamilies();

// Plausibility bounds (validateRigGeometry says why).
constexpr double kMinLengthM = 0.001;
constexpr double kMaxLengthM = 10.0;
constexpr double kMinReflectance = 0.01;

// Fields: tag_family (one of knownTagFamilies), tag_id (0..code_count-1),
// tag_size (metres, outer edge of the black border, in [1 mm, 10 m]),
// probe_center ([x, y, z] in W, metres, each within +-10 m), probe_radius
// (m, in [1 mm, 10 m]), probe_reflectance (in [0.01, 1], default 1),
// tag_white_albedo (the printed white's diffuse reflectance, in [0.01, 1],
// default 0.85), post_radius (m, in [0, probe_radius), default 0: no post)
// and post_albedo (the post's diffuse reflectance, 0 or in [0.01, 1],
// default 0: not a reference). Throws ConfigError.
RigGeometry loadRigFile(const std::string& path);

// Throws ConfigError when `rig` would not load back or cannot be written.
void saveRigFile(const std::string& path, const RigGeometry& rig);

void validateRigGeometry(const RigGeometry& rig, const std::string& path);

}  // namespace probelight::config
