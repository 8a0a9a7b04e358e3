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

// <dir>/lighting.json.
std::filesystem::path lightingStatePath(const std::filesystem::path& state_dir);
bool saveLighting(const std::filesystem::path& state_dir, const StoredLighting& lighting, std::string& error);
// nullopt with an empty error when there is no file yet; nullopt with a
// one-line error naming the file and what is wrong when it is unreadable
// (the kiosk then starts as if there were none, and says so).
std::optional<StoredLighting> loadLighting(const std::filesystem::path& state_dir, std::string& error);

}  // namespace probelight
