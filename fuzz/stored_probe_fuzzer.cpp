// The kiosk's stored probe over views (<state>/probe.bin, loadProbe): a cube
// of finite, bounded texels whose count matches its face size, or nothing
// with one line naming the file.
#include <cmath>

#include "fuzz/fuzz_input.hpp"
#include "stages/state_store.hpp"

using namespace probelight;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path& folder = fuzz::workFolder();
  const std::string path = probeStatePath(folder).string();
  fuzz::writeInput(data, size, probeStatePath(folder).filename().string());
  std::string error;
  const std::optional<StoredProbe> probe = loadProbe(folder, error);
  if (!probe) {
    fuzz::requireOneLineNaming(error, path);
    return 0;
  }
  fuzz::require(error.empty(), "an error message beside a loaded probe");
  fuzz::require(probe->face_size >= 1 && probe->face_size <= kMaxStoredProbeFaceSize, "a face size out of 1..1024 accepted");
  fuzz::require(probe->texels.size() == 6u * probe->face_size * probe->face_size, "a texel count that is not a cube accepted");
  fuzz::require(probe->exposure_product == 0.0 ||
                    (probe->exposure_product >= kMinStoredExposure && probe->exposure_product <= kMaxStoredExposure),
                "an exposure out of 0 or 1e-3..1e9 accepted");
  for (const glm::vec4& t : probe->texels) {
    fuzz::require(std::isfinite(t.r) && std::isfinite(t.g) && std::isfinite(t.b) && std::isfinite(t.a),
                  "a non-finite texel accepted");
    fuzz::require(t.r >= 0.0f && t.g >= 0.0f && t.b >= 0.0f && t.r <= kMaxStoredRadiance &&
                      t.g <= kMaxStoredRadiance && t.b <= kMaxStoredRadiance,
                  "a radiance out of 0..1e6 accepted");
    fuzz::require(std::abs(t.a) <= kMaxStoredProbeConfidence, "a confidence beyond 1e9 accepted");
  }
  return 0;
}
