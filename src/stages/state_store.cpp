#include "stages/state_store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

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
    const nlohmann::json json = nlohmann::json::parse(in);
    if (json.value("format", "") != "probelight lighting 1") {
      error = path.string() + ": not a probelight lighting file (format)";
      return std::nullopt;
    }
    auto vec3 = [](const nlohmann::json& v) {
      const glm::dvec3 value(v.at(0).get<double>(), v.at(1).get<double>(), v.at(2).get<double>());
      if (!std::isfinite(value.x) || !std::isfinite(value.y) || !std::isfinite(value.z))
        throw std::runtime_error("a number is not finite");
      return value;
    };
    StoredLighting stored;
    stored.placement = json.value("placement", "");
    for (const auto& l : json.at("lights")) {
      ibl::DomeLight light;
      light.direction_w = vec3(l.at("direction"));
      light.rgb = vec3(l.at("rgb"));
      light.spread_rad = l.at("spread_rad").get<double>();
      light.solid_angle_sr = l.value("solid_angle_sr", 0.0);
      if (!(std::abs(glm::length(light.direction_w) - 1.0) < 1e-6) || light.rgb.r < 0 || light.rgb.g < 0 ||
          light.rgb.b < 0 || !(light.spread_rad >= 0.0))
        throw std::runtime_error("a light is not a unit direction with a non-negative colour");
      stored.lights.push_back(light);
    }
    const auto& d = json.at("dominant_light");
    stored.dominant.found = d.at("found").get<bool>();
    stored.dominant.direction_w = vec3(d.at("direction"));
    stored.dominant.rgb = vec3(d.at("rgb"));
    for (const auto& l : json.value("clipped_lights", nlohmann::json::array())) {
      ibl::ClippedLight light;
      light.direction_w = vec3(l.at("direction"));
      light.irradiance_rgb = vec3(l.at("irradiance_rgb"));
      light.texels = l.at("texels").get<std::vector<std::uint32_t>>();
      light.texel_share = l.at("texel_share").get<std::vector<float>>();
      const double share = l.at("share_at_fit").get<double>();
      if (!(std::abs(glm::length(light.direction_w) - 1.0) < 1e-6) || light.irradiance_rgb.r < 0 ||
          light.irradiance_rgb.g < 0 || light.irradiance_rgb.b < 0 || light.texels.size() != light.texel_share.size() ||
          !(share >= 0.0 && share <= 1.0))
        throw std::runtime_error("a clipped light is not a unit direction with a non-negative irradiance and its texels");
      stored.clipped_lights.push_back(std::move(light));
      stored.clipped_share_at_fit.push_back(share);
    }
    stored.exposure_at_fit = json.value("exposure_at_fit", 1.0);
    if (!(stored.exposure_at_fit > 0.0) || !std::isfinite(stored.exposure_at_fit))
      throw std::runtime_error("exposure_at_fit is not a positive number");
    return stored;
  } catch (const std::exception& e) {
    error = path.string() + ": " + e.what();
    return std::nullopt;
  }
}

}  // namespace probelight
