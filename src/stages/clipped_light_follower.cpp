#include "stages/clipped_light_follower.hpp"

#include <algorithm>

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

std::vector<double> ClippedLightFollower::sharesFor(const ibl::CubeMapRGB& live, double clip_level,
                                                    const std::vector<std::uint8_t>* resolved) const {
  std::vector<double> share(lights_.size(), 1.0);
  for (std::size_t k = 0; k < lights_.size(); ++k) {
    const double at_fit = share_at_fit_[k];
    // Nothing of it clipped in the map at the fit: it cannot be followed.
    if (!(at_fit > 0.0)) continue;
    const ibl::ClippedShares now = ibl::clippedShares(lights_[k], live, clip_level, resolved);
    // A light nothing of which clips has gone, whatever was resolved.
    share[k] = now.still_clipped > 0.0
                   ? std::min(1.0, now.still_clipped / std::max(at_fit - now.resolved, now.still_clipped))
                   : 0.0;
  }
  return share;
}

}  // namespace probelight
