// The kiosk's stored lighting (<state>/lighting.json, loadLighting): lights
// within the documented bounds, or nothing with one line naming the file.
#include <algorithm>

#include "fuzz/fuzz_input.hpp"
#include "stages/state_store.hpp"

using namespace probelight;

namespace {

bool finiteVector(const glm::dvec3& v) { return fuzz::finite(v.x) && fuzz::finite(v.y) && fuzz::finite(v.z); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path& folder = fuzz::workFolder();
  const std::string path = lightingStatePath(folder).string();
  fuzz::writeInput(data, size, lightingStatePath(folder).filename().string());
  std::string error;
  const std::optional<StoredLighting> lighting = loadLighting(folder, error);
  if (!lighting) {
    fuzz::requireOneLineNaming(error, path);
    return 0;
  }
  fuzz::require(error.empty(), "an error message beside a loaded lighting");
  fuzz::require(!lighting->lights.empty() && lighting->lights.size() <= kMaxStoredLights, "a light count out of 1..64 accepted");
  for (const ibl::DomeLight& light : lighting->lights) {
    fuzz::require(finiteVector(light.direction_w) && std::abs(glm::length(light.direction_w) - 1.0) < 1e-6,
                  "a light direction that is not a unit vector accepted");
    fuzz::require(finiteVector(light.rgb) && light.rgb.r >= 0.0 && light.rgb.g >= 0.0 && light.rgb.b >= 0.0 &&
                      std::max({light.rgb.r, light.rgb.g, light.rgb.b}) <= kMaxStoredRadiance,
                  "a light's irradiance out of 0..1e6 accepted");
    fuzz::require(fuzz::finite(light.spread_rad) && fuzz::finite(light.solid_angle_sr), "a non-finite light size accepted");
  }
  fuzz::require(fuzz::finite(lighting->exposure_at_fit) && lighting->exposure_at_fit >= kMinStoredExposure &&
                    lighting->exposure_at_fit <= kMaxStoredExposure,
                "an exposure out of 1e-3..1e9 accepted");
  return 0;
}
