// The kiosk's state directory: the last good lighting, kept across restarts
// and power cuts (on the board, /var/lib/probelight).
//
// Files are replaced atomically: the new contents go to a temporary file in
// the same directory, are fsync'ed, and the temporary file is renamed over
// the old one, then the directory is fsync'ed. rename() within a file system
// is atomic, so a power cut or a kill at any point leaves either the old file
// or the new one, never a torn one; a leftover temporary file is ignored.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "ibl/light_dome.hpp"
#include "ibl/white_reference.hpp"

namespace probelight {

// `before_rename` runs after the temporary file is durable and before it
// replaces `path` (tests kill the process there).
bool writeFileAtomically(const std::filesystem::path& path, const std::string& contents, std::string& error,
                         const std::function<void()>& before_rename = {});

struct StoredLighting {
  std::vector<ibl::DomeLight> lights;
  ibl::DominantLight dominant;
  std::string placement;
  // The fit's clipped lights (a bracket's or the white border's), with what
  // the kiosk follows them against: the share of each that clipped in the
  // fit's map, and the fit frame's exposure time x gain (1: unknown).
  // Optional in the file: older files have none.
  std::vector<ibl::ClippedLight> clipped_lights;
  std::vector<double> clipped_share_at_fit;
  double exposure_at_fit = 1.0;
};

// What loadLighting accepts; anything else is a damaged or hand-edited file.
// Lights: lights.count's range. Radiance: a half-float map (the largest
// storage) holds at most 65504 per texel, 8.2e5 over the whole sphere, so no
// fit gives more than 1e6. Texels: six faces of maps.face_size's largest,
// 1024. Exposure (time in microseconds x gain; 1 when unknown): 1e-3 to 1e9
// spans any sensor's shortest and longest.
inline constexpr std::size_t kMaxStoredLights = 64;
inline constexpr double kMaxStoredRadiance = 1e6;
inline constexpr std::size_t kMaxStoredTexels = 6u * 1024u * 1024u;
inline constexpr double kMinStoredExposure = 1e-3;
inline constexpr double kMaxStoredExposure = 1e9;

// <dir>/lighting.json.
std::filesystem::path lightingStatePath(const std::filesystem::path& state_dir);
bool saveLighting(const std::filesystem::path& state_dir, const StoredLighting& lighting, std::string& error);
// nullopt with an empty error when there is no file yet; nullopt with a
// one-line error naming the file and what is wrong when it is unreadable
// (the kiosk then starts as if there were none, and says so).
std::optional<StoredLighting> loadLighting(const std::filesystem::path& state_dir, std::string& error);

// The probe merged over views (stages/probe_merge.hpp), kept with the
// lighting: <dir>/probe.bin. A text header line,
//   probelight probe 1 <face_size> <exposure time x gain, 0: unknown>
// then the texels (rgb radiance, signed confidence), 4 little-endian
// float32 each, face-major: 384 KiB for 64^2 faces. Binary because the
// confidence and the radiance above the 8-bit range are not an image's.
struct StoredProbe {
  int face_size = 0;
  double exposure_product = 0.0;
  std::vector<glm::vec4> texels;
};
inline constexpr int kMaxStoredProbeFaceSize = 1024;
inline constexpr float kMaxStoredProbeConfidence = 1e9f;
std::filesystem::path probeStatePath(const std::filesystem::path& state_dir);
bool saveProbe(const std::filesystem::path& state_dir, const StoredProbe& probe, std::string& error);
// As loadLighting: nullopt with an empty error when there is no file,
// nullopt with one line naming the file and the field when it is not a
// probe this program wrote (header, face_size, exposure, texels: their
// count, or a negative or non-finite value).
std::optional<StoredProbe> loadProbe(const std::filesystem::path& state_dir, std::string& error);

}  // namespace probelight
