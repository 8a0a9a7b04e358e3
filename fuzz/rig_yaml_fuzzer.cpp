// rig.yaml (config::loadRigFile): a rig within the documented bounds, or one
// ConfigError line naming the file.
#include "config/rig_file.hpp"
#include "fuzz/fuzz_input.hpp"

using namespace probelight;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = fuzz::writeInput(data, size, "rig.yaml");
  try {
    const RigGeometry rig = config::loadRigFile(path);
    for (const double length : {rig.tag_size_m, rig.probe_radius_m})
      fuzz::require(fuzz::finite(length) && length >= config::kMinLengthM && length <= config::kMaxLengthM,
                    "a length out of 1 mm..10 m accepted");
    for (int i = 0; i < 3; ++i)
      fuzz::require(fuzz::finite(rig.probe_center_w[i]) && std::abs(rig.probe_center_w[i]) <= config::kMaxLengthM,
                    "a probe centre beyond 10 m accepted");
    for (const double reflectance : {rig.probe_reflectance, rig.tag_white_albedo})
      fuzz::require(reflectance >= config::kMinReflectance && reflectance <= 1.0, "a reflectance out of [0.01, 1] accepted");
    fuzz::require(rig.post_radius_m >= 0.0 && rig.post_radius_m < rig.probe_radius_m, "a post wider than the ball accepted");
    fuzz::require(rig.post_albedo == 0.0 || (rig.post_albedo >= config::kMinReflectance && rig.post_albedo <= 1.0),
                  "a post albedo out of range accepted");
    fuzz::require(rig.tag_id >= 0, "a negative tag id accepted");
  } catch (const config::ConfigError& error) {
    fuzz::requireOneLineNaming(error.what(), path);
  }
  return 0;
}
