#include "stages/clipped_light_follower.hpp"

#include <algorithm>
#include <cmath>

#include "ibl/color_transfer.hpp"

namespace probelight {

double exposureProduct(double exposure_us, double analogue_gain) {
  return exposure_us > 0.0 ? exposure_us * (analogue_gain > 0.0 ? analogue_gain : 1.0) : 1.0;
}

void ClippedLightFollower::follow(std::vector<ibl::ClippedLight> lights, const ibl::CubeMapRGB& map_at_fit,
                                  double clip_level, double exposure_at_fit) {
  lights_ = std::move(lights);
  share_at_fit_.clear();
  for (const ibl::ClippedLight& light : lights_) share_at_fit_.push_back(ibl::stillClippedShare(light, map_at_fit, clip_level));
  exposure_at_fit_ = exposure_at_fit;
}

void ClippedLightFollower::restore(std::vector<ibl::ClippedLight> lights, std::vector<double> share_at_fit,
                                   double exposure_at_fit) {
  lights_ = std::move(lights);
  share_at_fit_ = std::move(share_at_fit);
  share_at_fit_.resize(lights_.size(), 0.0);
  exposure_at_fit_ = exposure_at_fit;
}

std::vector<double> ClippedLightFollower::sharesFor(const ibl::CubeMapRGB& live, double clip_level) const {
  std::vector<double> share(lights_.size(), 1.0);
  for (std::size_t k = 0; k < lights_.size(); ++k) {
    const double at_fit = share_at_fit_[k];
    // Nothing of it clipped in the map at the fit: it cannot be followed.
    if (at_fit > 0.0) share[k] = std::min(1.0, ibl::stillClippedShare(lights_[k], live, clip_level) / at_fit);
  }
  return share;
}

std::vector<double> ClippedLightFollower::scalesFor(const ibl::CubeMapRGB& live, double clip_level,
                                                    double exposure_now) const {
  const double exposure_ratio = exposure_now / exposure_at_fit_;
  std::vector<double> scale = sharesFor(live, clip_level);
  for (double& s : scale) s *= exposure_ratio;
  return scale;
}

double ClippedLightFollower::partlyClippingShareOfIrradiance(const std::vector<double>& shares,
                                                             const std::vector<ibl::DomeLight>& dome) const {
  double largest = 0.0;
  for (std::size_t k = 0; k < lights_.size() && k < shares.size(); ++k) {
    if (!(shares[k] > 0.0 && shares[k] < 1.0)) continue;  // whole, gone, or not a number
    const glm::dvec3 toward = lights_[k].direction_w;
    const double taken = (1.0 - shares[k]) * ibl::luminance(lights_[k].irradiance_rgb);
    // The dome is fitted to the whole measured light, this one's included.
    double there = 0.0;
    for (const ibl::DomeLight& light : dome)
      there += ibl::luminance(light.rgb) * std::max(0.0, glm::dot(light.direction_w, toward));
    // A dome that says nothing there (none yet): the light alone.
    const double whole = there > 0.0 ? std::max(there, ibl::luminance(lights_[k].irradiance_rgb))
                                     : ibl::luminance(lights_[k].irradiance_rgb);
    if (whole > 0.0 && std::isfinite(taken / whole)) largest = std::max(largest, taken / whole);
  }
  return largest;
}

}  // namespace probelight
