// What the post reference read and did (ibl/post_reference.hpp), for
// analysis.json (`analyze`, `render`) and report.json (`run`) alike.
#pragma once

#include "core/types.hpp"
#include "ibl/post_reference.hpp"

namespace probelight {

// Json: nlohmann::json or nlohmann::ordered_json.
template <typename Json>
Json postCorrectionJson(const ibl::PostCorrection& correction, const RigGeometry& rig) {
  auto vec3 = [](const glm::dvec3& v) { return Json::array({v.x, v.y, v.z}); };
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

}  // namespace probelight
