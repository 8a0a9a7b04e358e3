#include "ibl/lighting_fit.hpp"

#include <chrono>
#include <limits>
#include <numbers>

#include "ibl/hdr_bracket.hpp"

namespace probelight::ibl {

const char* toString(LightingFitMethod method) {
  switch (method) {
    case LightingFitMethod::kEightBit: return "none";
    case LightingFitMethod::kBracket: return "bracket";
    case LightingFitMethod::kWhiteBorder: return "white_border";
    case LightingFitMethod::kWhiteBorderAndPost: return "white_border_and_post";
  }
  return "none";
}

LightingFit fitLighting(const LightingFitInputs& inputs, const LightingFitSettings& settings) {
  const CubeMapRGB& map_8bit = *inputs.map_8bit;
  const std::vector<float>* validity = inputs.validity;
  // Texels at or above this clipped in the camera (the merge's clip code,
  // through the ball's reflectance); an 8-bit map holds nothing above
  // 1 / reflectance.
  const double clip_level = clippedMapLevel(HdrMergeSettings{settings.camera_transfer}, inputs.rig.probe_reflectance);
  const double ceiling_8bit = 1.0 / inputs.rig.probe_reflectance;
  LightingFit fit;
  std::vector<std::uint8_t> clipped_mask;
  std::optional<CubeMapRGB> corrected;
  const bool have_hdr = inputs.hdr_map && inputs.view;
  if (inputs.view) {
    WhiteBorderSettings border_settings;
    border_settings.camera_transfer = settings.camera_transfer;
    clipped_mask = clippedTexelMask(*inputs.view, inputs.read_pixel, border_settings.clip_code, map_8bit.face_size);
    if (inputs.white_ring) {
      const auto start = std::chrono::steady_clock::now();
      fit.border = readWhiteBorder(inputs.view->camera, inputs.view->pose, *inputs.white_ring, inputs.read_pixel,
                                   border_settings);
      corrected = map_8bit;
      fit.border_correction = correctClippedWithWhiteBorder(*corrected, validity, *fit.border,
                                                            inputs.rig.tag_white_albedo, clip_level, &clipped_mask);
      const bool border_used = fit.border_correction->status == WhiteReferenceStatus::kCorrected;
      if (border_used && settings.post_reference) {
        PostReadingSettings post_settings;
        post_settings.camera_transfer = settings.camera_transfer;
        fit.post = correctClippedWithPost(*corrected, map_8bit, validity, clip_level, &clipped_mask, *fit.border,
                                          inputs.rig, inputs.view->camera, inputs.view->pose, inputs.read_pixel,
                                          post_settings);
      }
      fit.border_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      if (!have_hdr && settings.white_reference && fit.post && fit.post->fit.status == DiffuseFitStatus::kInconsistent)
        fit.warnings.push_back("the ball's post: " + fit.post->fit.message);
      const WhiteReferenceStatus status = fit.border_correction->status;
      if (!have_hdr && settings.white_reference && !border_used &&
          (status == WhiteReferenceStatus::kBorderDarker ||
           (status == WhiteReferenceStatus::kBorderUnusable && fit.border_correction->clipped_upper_sr > 0.0)))
        fit.warnings.push_back("the ball's highlights clip and the tag's white border cannot restore them: " +
                               fit.border_correction->message);
      if (!border_used) corrected.reset();
    }
  }
  if (have_hdr) {
    fit.method = LightingFitMethod::kBracket;
    fit.fitted_map = *inputs.hdr_map;
  } else if (settings.white_reference && corrected) {
    fit.method = fit.post && fit.post->fit.status == DiffuseFitStatus::kRefined ? LightingFitMethod::kWhiteBorderAndPost
                                                                               : LightingFitMethod::kWhiteBorder;
    fit.fitted_map = std::move(corrected);
  }
  const CubeMapRGB& fitted = fit.fitted_map ? *fit.fitted_map : map_8bit;
  if (fit.fitted_map)
    fit.clipped_lights = clippedLights(fitted, map_8bit, validity, clip_level, &clipped_mask, settings.max_clipped_lights);
  fit.dome = fitLightDome(fitted, validity, settings.dome);
  // Nothing in a bracket's or a corrected map is clipped any more.
  const double dominant_clip = fit.fitted_map ? std::numeric_limits<double>::infinity() : ceiling_8bit;
  fit.dominant = findDominantLight(fitted, validity, fit.dome, dominant_clip, settings.dome);
  return fit;
}

void setClippedLights(SceneLighting& lighting, const std::vector<ClippedLight>& lights,
                      const std::vector<double>& scale) {
  lighting.clipped_direction_w = {};
  lighting.clipped_diffuse_rgb = {};
  for (std::size_t k = 0; k < lights.size() && k < lighting.clipped_direction_w.size(); ++k) {
    const double at = k < scale.size() ? scale[k] : 1.0;
    lighting.clipped_direction_w[k] = glm::vec3(lights[k].direction_w);
    lighting.clipped_diffuse_rgb[k] = glm::vec3(at * lights[k].irradiance_rgb / std::numbers::pi);
  }
}

}  // namespace probelight::ibl
