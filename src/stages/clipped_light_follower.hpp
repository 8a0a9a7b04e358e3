// The last fit's clipped lights, followed between fits. The frame-rate maps
// are 8-bit, and the clipped lights carry what they clip. After each map
// update each light is scaled by the share of its texels that still clip
// now over the share that did at the fit (a sun gone behind a cloud, a lamp
// switched off: 0). The exposure and white balance since the fit (auto
// exposure runs again after one) are the lights stage's, for every fitted
// light alike (stages/frame_response.hpp); the fit's exposure is kept here
// to be stored with the lights. Pure: the caller reads the map back.
#pragma once

#include <cstdint>
#include <vector>

#include "ibl/cube_map.hpp"
#include "ibl/white_reference.hpp"

namespace probelight {

class ClippedLightFollower {
 public:
  // A fit's lights, followed against the 8-bit map they were found beside
  // and the fit frame's exposure time x gain (1: unknown).
  void follow(std::vector<ibl::ClippedLight> lights, const ibl::CubeMapRGB& map_at_fit, double clip_level,
              double exposure_at_fit);
  // Lights kept from an earlier run, with what they were followed against
  // (a missing share is 0: that light cannot be followed and keeps scale 1).
  void restore(std::vector<ibl::ClippedLight> lights, std::vector<double> share_at_fit, double exposure_at_fit);

  // Each light's share of what clipped at the fit that still clips in a
  // later map `live` of the same size, in [0, 1] (1: a light that cannot be
  // followed). `resolved` (per texel of `live`, or null): texels a view
  // sharper than the fit's bracket has shown to hold something else (a sun
  // the bracket saw smeared over the ball's rim, now seen in one texel, the
  // rest sky): they are no longer the light's, and their going out of the
  // clip does not dim it while the rest of it still clips.
  std::vector<double> sharesFor(const ibl::CubeMapRGB& live, double clip_level,
                                const std::vector<std::uint8_t>* resolved = nullptr) const;

  bool empty() const { return lights_.empty(); }
  const std::vector<ibl::ClippedLight>& lights() const { return lights_; }
  const std::vector<double>& shareAtFit() const { return share_at_fit_; }
  double exposureAtFit() const { return exposure_at_fit_; }

 private:
  std::vector<ibl::ClippedLight> lights_;
  std::vector<double> share_at_fit_;
  double exposure_at_fit_ = 1.0;
};

// Exposure time times gain (1 when the source cannot say): camera-linear
// values scale with it.
double exposureProduct(double exposure_us, double analogue_gain);

}  // namespace probelight
