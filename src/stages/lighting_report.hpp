// The lighting fit (ibl/lighting_fit.hpp) as JSON: the dome, the dominant
// light, the clipped lights, the post, the white border. One writer each for
// analysis.json (`analyze`, `render`) and report.json (`run`), where the two
// files share a layout; the white border has one layout per file (report.json
// keeps its summary, analysis.json the whole reading).
// Json: nlohmann::json or nlohmann::ordered_json.
#pragma once

#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "core/types.hpp"
#include "ibl/light_dome.hpp"
#include "ibl/post_reference.hpp"
#include "ibl/white_reference.hpp"

namespace probelight {

template <typename Json>
Json vec3Json(const glm::dvec3& v) {
  return Json::array({v.x, v.y, v.z});
}

template <typename Json>
Json domeLightsJson(const std::vector<ibl::DomeLight>& dome) {
  Json lights = Json::array();
  for (const ibl::DomeLight& light : dome)
    lights.push_back({{"direction", vec3Json<Json>(light.direction_w)},
                      {"rgb", vec3Json<Json>(light.rgb)},
                      {"spread_deg", glm::degrees(light.spread_rad)}});
  return lights;
}

template <typename Json>
Json dominantLightJson(const ibl::DominantLight& light) {
  return {{"direction", vec3Json<Json>(light.direction_w)},
          {"rgb", vec3Json<Json>(light.rgb)},
          {"from_clipped_region", light.from_clipped_region}};
}

template <typename Json>
Json clippedLightsJson(const std::vector<ibl::ClippedLight>& clipped) {
  Json lights = Json::array();
  for (const ibl::ClippedLight& light : clipped)
    lights.push_back({{"direction", vec3Json<Json>(light.direction_w)},
                      {"irradiance_rgb", vec3Json<Json>(light.irradiance_rgb)}});
  return lights;
}

// Json: nlohmann::json or nlohmann::ordered_json.
template <typename Json>
Json postCorrectionJson(const ibl::PostCorrection& correction, const RigGeometry& rig) {
  const auto vec3 = vec3Json<Json>;
  const ibl::PostReading& reading = correction.reading;
  Json references = Json::array();
  for (const ibl::DiffuseReference& reference : reading.references)
    references.push_back(
        {{"normal", vec3(reference.normal_w)}, {"irradiance_rgb", vec3(reference.irradiance_rgb)}, {"pixels", reference.pixels}});
  Json regions = Json::array();
  for (std::size_t k = 0; k < correction.fit.region_scale_rgb.size(); ++k)
    regions.push_back({{"direction", vec3(correction.fit.region_direction_w[k])},
                       {"scale_rgb", vec3(correction.fit.region_scale_rgb[k])}});
  return {{"status", ibl::toString(reading.status)},
          {"message", reading.message},
          {"post_radius", rig.post_radius_m},
          {"post_albedo", rig.post_albedo},
          {"pixels_seen", reading.pixels_seen},
          {"pixels_clipped", reading.pixels_clipped},
          {"pixels_dark", reading.pixels_dark},
          {"references", references},
          {"fit",
           {{"status", ibl::toString(correction.fit.status)},
            {"message", correction.fit.message},
            {"rms_relative_before", correction.fit.rms_relative_before},
            {"rms_relative_after", correction.fit.rms_relative_after},
            {"regions", regions}}}};
}

// report.json's white_border: the summary of the border's reading and what
// it did (`clipped`: the lights it gave the clipped highlights).
inline nlohmann::json whiteBorderReportJson(const ibl::WhiteBorderReading& reading,
                                            const ibl::WhiteReferenceResult& result,
                                            const std::vector<ibl::ClippedLight>& clipped) {
  using Json = nlohmann::json;
  return {{"border", ibl::toString(reading.status)},
          {"correction", ibl::toString(result.status)},
          {"message", result.message},
          {"patches_lit", reading.patches_lit},
          {"patches", reading.patches},
          {"clipped_upper_sr", result.clipped_upper_sr},
          {"border_irradiance_rgb", vec3Json<Json>(result.border_irradiance_rgb)},
          {"ball_irradiance_rgb", vec3Json<Json>(result.map_irradiance_rgb)},
          {"clipped_lights", clippedLightsJson<Json>(clipped)}};
}

// analysis.json's hdr.white_border: the whole reading, and the correction
// it gives (used or not).
inline nlohmann::ordered_json whiteBorderAnalysisJson(const ibl::WhiteBorderReading& reading,
                                                      const ibl::WhiteReferenceResult& result,
                                                      double tag_white_albedo) {
  using Json = nlohmann::ordered_json;
  Json border = {{"status", ibl::toString(reading.status)},
                 {"message", reading.message},
                 {"tag_white_albedo", tag_white_albedo},
                 {"patches", reading.patches},
                 {"patches_lit", reading.patches_lit},
                 {"patches_shadowed", reading.patches_shadowed},
                 {"patches_clipped", reading.patches_clipped},
                 {"patches_dark", reading.patches_dark}};
  if (reading.status == ibl::WhiteBorderStatus::kMeasured) border["linear_rgb"] = vec3Json<Json>(reading.linear_rgb);
  border["correction"] = {{"status", ibl::toString(result.status)},
                          {"message", result.message},
                          {"border_irradiance_rgb", vec3Json<Json>(result.border_irradiance_rgb)},
                          {"ball_irradiance_rgb", vec3Json<Json>(result.map_irradiance_rgb)},
                          {"added_radiance_rgb", vec3Json<Json>(result.added_radiance_rgb)},
                          {"clipped_upper_sr", result.clipped_upper_sr},
                          {"clipped_lower_sr", result.clipped_lower_sr}};
  return border;
}

}  // namespace probelight
