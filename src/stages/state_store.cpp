#include "stages/state_store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/file_bytes.hpp"

namespace probelight {

namespace {

std::string systemError(const std::string& what, const std::filesystem::path& path) {
  return what + " " + path.string() + ": " + std::strerror(errno);
}

}  // namespace

bool writeFileAtomically(const std::filesystem::path& path, const std::string& contents, std::string& error,
                         const std::function<void()>& before_rename) {
  const std::filesystem::path directory = path.has_parent_path() ? path.parent_path() : ".";
  // Hidden, in the same directory (rename is atomic within a file system
  // only), and per process.
  std::string temporary_name = ".";
  temporary_name += path.filename().string();
  temporary_name += ".tmp.";
  temporary_name += std::to_string(::getpid());
  const std::filesystem::path temporary = directory / temporary_name;
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    error = systemError("cannot create", temporary);
    return false;
  }
  std::size_t written = 0;
  while (written < contents.size()) {
    const ssize_t n = ::write(fd, contents.data() + written, contents.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error = systemError("cannot write", temporary);
      ::close(fd);
      ::unlink(temporary.c_str());
      return false;
    }
    written += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    error = systemError("cannot sync", temporary);
    ::close(fd);
    ::unlink(temporary.c_str());
    return false;
  }
  ::close(fd);
  if (before_rename) before_rename();
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    error = systemError("cannot replace", path);
    ::unlink(temporary.c_str());
    return false;
  }
  // The rename itself is durable once the directory is.
  const int directory_fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (directory_fd >= 0) {
    ::fsync(directory_fd);
    ::close(directory_fd);
  }
  return true;
}

std::filesystem::path lightingStatePath(const std::filesystem::path& state_dir) { return state_dir / "lighting.json"; }

bool saveLighting(const std::filesystem::path& state_dir, const StoredLighting& lighting, std::string& error) {
  std::error_code ec;
  std::filesystem::create_directories(state_dir, ec);
  if (ec) {
    error = "cannot create the state directory " + state_dir.string() + ": " + ec.message();
    return false;
  }
  nlohmann::json lights = nlohmann::json::array();
  for (const ibl::DomeLight& l : lighting.lights)
    lights.push_back({{"direction", {l.direction_w.x, l.direction_w.y, l.direction_w.z}},
                      {"rgb", {l.rgb.r, l.rgb.g, l.rgb.b}},
                      {"spread_rad", l.spread_rad},
                      {"solid_angle_sr", l.solid_angle_sr}});
  nlohmann::json clipped = nlohmann::json::array();
  for (std::size_t k = 0; k < lighting.clipped_lights.size(); ++k) {
    const ibl::ClippedLight& l = lighting.clipped_lights[k];
    clipped.push_back({{"direction", {l.direction_w.x, l.direction_w.y, l.direction_w.z}},
                       {"irradiance_rgb", {l.irradiance_rgb.r, l.irradiance_rgb.g, l.irradiance_rgb.b}},
                       {"texels", l.texels},
                       {"texel_share", l.texel_share},
                       {"share_at_fit", k < lighting.clipped_share_at_fit.size() ? lighting.clipped_share_at_fit[k] : 0.0}});
  }
  const auto& d = lighting.dominant;
  const nlohmann::json json = {
      {"format", "probelight lighting 1"},
      {"placement", lighting.placement},
      {"lights", lights},
      {"dominant_light",
       {{"found", d.found},
        {"direction", {d.direction_w.x, d.direction_w.y, d.direction_w.z}},
        {"rgb", {d.rgb.r, d.rgb.g, d.rgb.b}}}},
      {"clipped_lights", clipped},
      {"exposure_at_fit", lighting.exposure_at_fit}};
  return writeFileAtomically(lightingStatePath(state_dir), json.dump(2) + "\n", error);
}

std::optional<StoredLighting> loadLighting(const std::filesystem::path& state_dir, std::string& error) {
  error.clear();
  const std::filesystem::path path = lightingStatePath(state_dir);
  std::ifstream in(path);
  if (!in) {
    if (std::filesystem::exists(path)) error = path.string() + ": cannot be read";
    return std::nullopt;
  }
  try {
    // The file nests 3 deep; nlohmann builds (and frees) nested values
    // recursively, so 10^6 brackets overflowed the stack (SIGSEGV). The
    // callback sees each value's depth as it is read, before it is built.
    constexpr int kMaxDepth = 16;
    const nlohmann::json json =
        nlohmann::json::parse(in, [](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
          if (depth > kMaxDepth) throw std::runtime_error("nested deeper than " + std::to_string(kMaxDepth) + " levels");
          return true;
        });
    if (json.value("format", "") != "probelight lighting 1") {
      error = path.string() + ": not a probelight lighting file (format)";
      return std::nullopt;
    }
    // Every value is checked against what a fit can produce, so a file
    // edited by hand or damaged on disk is refused whole, with the field
    // named, and the kiosk starts as if there were none.
    auto fail = [](const std::string& field, const std::string& what) {
      throw std::runtime_error("field '" + field + "': " + what);
    };
    auto number = [&](const nlohmann::json& v, const std::string& field, double low, double high) {
      if (!v.is_number()) fail(field, "not a number");
      const double value = v.get<double>();
      if (!(value >= low && value <= high))
        fail(field, nlohmann::json(value).dump() + " is outside [" + nlohmann::json(low).dump() + ", " +
                        nlohmann::json(high).dump() + "]");
      return value;
    };
    auto vec3 = [&](const nlohmann::json& v, const std::string& field, double low, double high) {
      if (!v.is_array() || v.size() != 3) fail(field, "not 3 numbers");
      return glm::dvec3(number(v[0], field + "[0]", low, high), number(v[1], field + "[1]", low, high),
                        number(v[2], field + "[2]", low, high));
    };
    auto direction = [&](const nlohmann::json& v, const std::string& field) {
      const glm::dvec3 d = vec3(v, field, -1.0, 1.0);
      if (!(std::abs(glm::length(d) - 1.0) < 1e-6)) fail(field, "not a unit direction");
      return d;
    };
    auto array = [&](const nlohmann::json& v, const std::string& field, std::size_t low, std::size_t high) {
      if (!v.is_array()) fail(field, "not a list");
      if (v.size() < low || v.size() > high)
        fail(field, std::to_string(v.size()) + " entries, outside [" + std::to_string(low) + ", " +
                        std::to_string(high) + "]");
      return v;
    };
    StoredLighting stored;
    stored.placement = json.value("placement", "");
    const nlohmann::json& lights = array(json.at("lights"), "lights", 1, kMaxStoredLights);
    for (std::size_t i = 0; i < lights.size(); ++i) {
      const std::string field = "lights[" + std::to_string(i) + "]";
      const nlohmann::json& l = lights[i];
      ibl::DomeLight light;
      light.direction_w = direction(l.at("direction"), field + ".direction");
      light.rgb = vec3(l.at("rgb"), field + ".rgb", 0.0, kMaxStoredRadiance);
      light.spread_rad = number(l.at("spread_rad"), field + ".spread_rad", 0.0, M_PI);
      light.solid_angle_sr =
          number(l.value("solid_angle_sr", nlohmann::json(0.0)), field + ".solid_angle_sr", 0.0, 4.0 * M_PI);
      stored.lights.push_back(light);
    }
    const auto& d = json.at("dominant_light");
    if (!d.at("found").is_boolean()) fail("dominant_light.found", "not true or false");
    stored.dominant.found = d.at("found").get<bool>();
    stored.dominant.rgb = vec3(d.at("rgb"), "dominant_light.rgb", 0.0, kMaxStoredRadiance);
    // A fit that found none stores a zero direction.
    stored.dominant.direction_w = stored.dominant.found ? direction(d.at("direction"), "dominant_light.direction")
                                                        : vec3(d.at("direction"), "dominant_light.direction", -1.0, 1.0);
    const nlohmann::json& clipped =
        array(json.value("clipped_lights", nlohmann::json::array()), "clipped_lights", 0, kMaxStoredLights);
    for (std::size_t i = 0; i < clipped.size(); ++i) {
      const std::string field = "clipped_lights[" + std::to_string(i) + "]";
      const nlohmann::json& l = clipped[i];
      ibl::ClippedLight light;
      light.direction_w = direction(l.at("direction"), field + ".direction");
      light.irradiance_rgb = vec3(l.at("irradiance_rgb"), field + ".irradiance_rgb", 0.0, kMaxStoredRadiance);
      const nlohmann::json& texels = array(l.at("texels"), field + ".texels", 0, kMaxStoredTexels);
      const nlohmann::json& shares = array(l.at("texel_share"), field + ".texel_share", texels.size(), texels.size());
      for (std::size_t k = 0; k < texels.size(); ++k) {
        // Read as a number first: get<uint32_t> would turn -1 into 4294967295.
        light.texels.push_back(static_cast<std::uint32_t>(
            number(texels[k], field + ".texels[" + std::to_string(k) + "]", 0.0, kMaxStoredTexels - 1.0)));
        light.texel_share.push_back(
            static_cast<float>(number(shares[k], field + ".texel_share[" + std::to_string(k) + "]", 0.0, 1.0)));
      }
      stored.clipped_lights.push_back(std::move(light));
      stored.clipped_share_at_fit.push_back(number(l.at("share_at_fit"), field + ".share_at_fit", 0.0, 1.0));
    }
    stored.exposure_at_fit =
        number(json.value("exposure_at_fit", nlohmann::json(1.0)), "exposure_at_fit", kMinStoredExposure, kMaxStoredExposure);
    return stored;
  } catch (const std::exception& e) {
    error = path.string() + ": " + e.what();
    return std::nullopt;
  }
}

// --- the probe ---------------------------------------------------------------

namespace {

constexpr const char* kProbeMagic = "probelight probe 1";
// The file's floats are the host's: every board this runs on (ARM, x86) is
// little-endian.
static_assert(std::endian::native == std::endian::little, "probe.bin is little-endian float32");

std::size_t probeTexelCount(int face_size) {
  return 6u * static_cast<std::size_t>(face_size) * static_cast<std::size_t>(face_size);
}

}  // namespace

std::filesystem::path probeStatePath(const std::filesystem::path& state_dir) { return state_dir / "probe.bin"; }

bool saveProbe(const std::filesystem::path& state_dir, const StoredProbe& probe, std::string& error) {
  if (probe.face_size < 1 || probe.face_size > kMaxStoredProbeFaceSize ||
      probe.texels.size() != probeTexelCount(probe.face_size)) {
    error = "probe of " + std::to_string(probe.texels.size()) + " texels is not a cube of face size " +
            std::to_string(probe.face_size);
    return false;
  }
  std::error_code ec;
  std::filesystem::create_directories(state_dir, ec);
  if (ec) {
    error = "cannot create the state directory " + state_dir.string() + ": " + ec.message();
    return false;
  }
  std::ostringstream header;
  header.precision(17);
  header << kProbeMagic << " " << probe.face_size << " " << probe.exposure_product << "\n";
  std::string contents = header.str();
  const std::size_t header_size = contents.size();
  contents.resize(header_size + probe.texels.size() * sizeof(glm::vec4));
  std::memcpy(contents.data() + header_size, probe.texels.data(), probe.texels.size() * sizeof(glm::vec4));
  return writeFileAtomically(probeStatePath(state_dir), contents, error);
}

std::optional<StoredProbe> loadProbe(const std::filesystem::path& state_dir, std::string& error) {
  error.clear();
  const std::filesystem::path path = probeStatePath(state_dir);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return std::nullopt;
  // The largest face size's cube, and its header.
  const std::uint64_t max_bytes = probeTexelCount(kMaxStoredProbeFaceSize) * sizeof(glm::vec4) + 256;
  std::vector<std::uint8_t> bytes;
  std::string why;
  if (!readWholeFile(path.string(), max_bytes, bytes, why)) {
    error = path.string() + ": " + why;
    return std::nullopt;
  }
  auto fail = [&](const std::string& field, const std::string& what) {
    error = path.string() + ": field '" + field + "': " + what;
    return std::nullopt;
  };
  const auto newline = std::find(bytes.begin(), bytes.begin() + std::min<std::size_t>(bytes.size(), 128), '\n');
  if (newline == bytes.end() || newline == bytes.begin() + std::min<std::size_t>(bytes.size(), 128))
    return fail("header", std::string("no '") + kProbeMagic + " <face_size> <exposure>' line");
  const std::string header(bytes.begin(), newline);
  const std::string magic = kProbeMagic;
  if (header.rfind(magic + " ", 0) != 0) return fail("header", "not a probelight probe file");
  std::istringstream fields(header.substr(magic.size()));
  StoredProbe probe;
  std::string extra;
  if (!(fields >> probe.face_size) || probe.face_size < 1 || probe.face_size > kMaxStoredProbeFaceSize)
    return fail("face_size", "not a whole number in [1, " + std::to_string(kMaxStoredProbeFaceSize) + "]");
  if (!(fields >> probe.exposure_product) || !std::isfinite(probe.exposure_product) ||
      !(probe.exposure_product == 0.0 ||
        (probe.exposure_product >= kMinStoredExposure && probe.exposure_product <= kMaxStoredExposure)))
    return fail("exposure", "not 0 (unknown) or a number in [1e-3, 1e9]");
  if (fields >> extra) return fail("header", "more than face_size and exposure");
  const std::size_t texel_bytes = static_cast<std::size_t>(bytes.end() - (newline + 1));
  const std::size_t count = probeTexelCount(probe.face_size);
  if (texel_bytes != count * sizeof(glm::vec4))
    return fail("texels", std::to_string(texel_bytes) + " bytes, a cube of face size " +
                              std::to_string(probe.face_size) + " has " + std::to_string(count * sizeof(glm::vec4)));
  probe.texels.resize(count);
  std::memcpy(probe.texels.data(), &*(newline + 1), texel_bytes);
  for (std::size_t i = 0; i < count; ++i) {
    const glm::vec4& t = probe.texels[i];
    // Radiance as the lighting's bound. The confidence is 1/sigma^2 of a
    // direction, sigma at least a texel's angle / sqrt(12), summed over at
    // most memory_views (30): 1e8 rad^-2 at face size 1024, so 1e9 is
    // beyond any this program writes, and a larger one would freeze the
    // texel against every later view.
    const bool radiance_good = std::isfinite(t.r) && std::isfinite(t.g) && std::isfinite(t.b) && t.r >= 0.0f &&
                               t.g >= 0.0f && t.b >= 0.0f && t.r <= kMaxStoredRadiance &&
                               t.g <= kMaxStoredRadiance && t.b <= kMaxStoredRadiance;
    if (!radiance_good)
      return fail("texels[" + std::to_string(i) + "]",
                  "radiance negative, above " + std::to_string(static_cast<long>(kMaxStoredRadiance)) + " or not finite");
    if (!(std::abs(t.a) <= kMaxStoredProbeConfidence))
      return fail("texels[" + std::to_string(i) + "]", "confidence beyond 1e9 or not finite");
  }
  return probe;
}

}  // namespace probelight
