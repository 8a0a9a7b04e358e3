// A world-aligned probe gathered over many views of the mirror ball.
//
// One view of a ball cannot see the directions straight behind it, and
// squeezes those near them into the ball's rim, where one pixel spans many
// degrees. A hand-held camera moves, and so does its blind spot: each
// direction is seen well from some view. The accumulator keeps, per texel
// of a 64^2 cube, the radiance and a confidence, and lets each new view
// (ibl/probe_observation.hpp) update a texel in proportion to how sure it
// is of it, so that the best views of each direction win.
//
// The rule, per texel, for a new sample x (confidence c, sensor noise
// sigma_x) against the kept estimate m (confidence C, noise sigma_m):
//  - The light changed when m lies outside every value the new view could
//    have read for this texel: the luminances of its own samples within its
//    direction uncertainty (neighbours within 1/sqrt(c) radians), widened
//    by change_sigmas times the noise of both. Only a sample sure of its
//    direction to within max_search_texels can say so. Then the new sample replaces
//    the estimate, and so does the connected region around it whose samples
//    differ from the estimate by more than noise: a lamp switched on
//    appears whole, edges included, within the frame.
//  - Otherwise the difference is what a misplaced direction or noise
//    explains, and the estimate moves by c / (decay C + c) toward the
//    sample, its confidence becoming decay C + c. decay = 1 - 1/memory_views
//    lets a steady texel follow slow drift.
//  - A clipped sample is a lower bound: it raises an estimate below it
//    (beyond noise) and otherwise leaves it; an unclipped sample consistent
//    with a bound replaces the bound (a measurement says more).
// A texel no view has seen has confidence 0.
//
// Storage: one float RGBA cube: rgb the radiance, a the confidence,
// negative where the estimate is a lower bound (6 x 64^2 x 16 B = 384 KiB).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"

namespace probelight::ibl {

// Sensor noise of a sample, as one standard deviation of its luminance, in
// map units (camera linear / reflectance, at the reference exposure).
struct SampleNoise {
  CameraTransfer camera_transfer;
  double probe_reflectance = 1.0;
  // Read noise plus quantisation, in 8-bit codes at the reference exposure:
  // the simulator adds 1.5, a Pi camera's ISP output shows 1-3.
  double code_sigma = 2.0;
  // The largest value the reference exposure measures (its clip level in
  // map units); above it, a bracket measured the value in a shorter
  // exposure, with the same relative noise as this level has.
  double clip_level = 1.0;
};

// SampleNoise as a table: sigma() is one lookup, cheap enough for every
// texel of every frame. The table's bins are even in sqrt(level), fine
// enough (2048 below the clip level) that a bin spans a small part of a code
// step at every code but the lowest, where the sRGB-like transfers are
// linear and every step is the same.
class NoiseLookup {
 public:
  explicit NoiseLookup(const SampleNoise& noise);
  double sigma(double luminance) const;
  // The least sigma at any level: a bound for tests that must not miss.
  double smallestSigma() const { return smallest_sigma_; }

 private:
  static constexpr int kBins = 2048;
  std::vector<double> sigma_by_bin_;  // bin of sqrt(level / clip_level) -> sigma
  double code_sigma_ = 2.0;
  double clip_level_ = 1.0;
  double inverse_clip_level_ = 1.0;
  double smallest_sigma_ = 0.0;
};

struct ProbeAccumulatorSettings {
  int face_size = 64;
  // A change is this many noise sigmas outside what the view can explain:
  // 3 sigma leaves 0.3% of steady texels per view to a false alarm, which
  // costs nothing but that texel's history.
  double change_sigmas = 3.0;
  // The views a steady texel's estimate averages over (the older ones'
  // confidence decays by 1 - 1/memory_views at each new sample).
  double memory_views = 30.0;
  // A sample whose direction uncertainty spans more texels each way than
  // this cannot seed a change (it merges, or joins a change seeded by a
  // surer sample): at the ball's rim a pixel spans 10-20 degrees, and a
  // sun squeezed there smears over them.
  int max_search_texels = 3;
  SampleNoise noise;
};

// One view's measurement of every texel (ibl/probe_observation.hpp makes them).
struct ProbeObservation {
  explicit ProbeObservation(int face_size = 64);
  // Back to "seen nothing" at this face size, the storage kept.
  void reset(int face_size);
  int face_size() const { return radiance.face_size; }
  std::size_t texelCount() const { return confidence.size(); }

  CubeMapRGB radiance;
  // 1 / sigma^2 of the direction the sample really came from (rad^-2);
  // 0: this view did not see the texel.
  std::vector<float> confidence;
  std::vector<std::uint8_t> lower_bound;  // 1: clipped in every exposure of the view
  // Where the sample came from, for reports: 0 none, 1 the ball, 2 the
  // frame around the ball.
  std::vector<std::uint8_t> source;
};

struct AccumulateCounts {
  long seen = 0;       // texels the view saw
  long first = 0;      // ... that no view had seen before
  long merged = 0;     // ... averaged into a steady estimate
  long changed = 0;    // ... where the light changed: the view replaced the estimate
  long raised = 0;     // ... a clipped sample raised the estimate (lower bound)
  long kept = 0;       // ... a clipped sample consistent with the estimate: nothing to learn
  // The largest change of a texel's luminance, relative to its noise: below
  // 1 the maps made from the probe would not move.
  double largest_move_sigmas = 0.0;
};

class ProbeAccumulator {
 public:
  explicit ProbeAccumulator(ProbeAccumulatorSettings settings = {});

  // Merges one view. Throws std::invalid_argument for an observation of
  // another face size. Non-finite samples are taken as unseen.
  AccumulateCounts add(const ProbeObservation& view);
  void clear();
  // Every radiance times `factor` (> 0, finite): the reference exposure moved.
  void scaleRadiance(double factor);
  // Per channel (a white balance's move); all three finite and > 0, else nothing.
  void scaleRadiance(const glm::dvec3& factor_rgb);
  // The kept estimate of `texel` becomes a lower bound (a caller knows its
  // samples were biased low: read beside clipped pixels). Unseen: nothing.
  void demoteToLowerBound(std::size_t texel);

  int faceSize() const { return settings_.face_size; }
  const ProbeAccumulatorSettings& settings() const { return settings_; }
  bool empty() const { return seen_texels_ == 0; }
  long seenTexels() const { return seen_texels_; }
  // Share of the sphere's solid angle some view has seen.
  double seenSolidAngleFraction() const;

  glm::vec3 radiance(std::size_t texel) const { return glm::vec3(texels_[texel]); }
  float confidence(std::size_t texel) const { return std::abs(texels_[texel].a); }
  bool lowerBound(std::size_t texel) const { return texels_[texel].a < 0.0f; }
  float solidAngleSr(std::size_t texel) const {
    return texel_solid_angle_sr_[texel % texel_solid_angle_sr_.size()];
  }

  // The radiance as a cube map (0 where unseen), each channel at most
  // `clamp_level` (the live maps hold what an 8-bit camera shows; the rest
  // is the clipped lights').
  CubeMapRGB radianceMap(float clamp_level = INFINITY) const;
  CubeMapRGB radianceMap(const glm::vec3& clamp_rgb) const;
  // 1 where seen, 0 where not (EnvironmentMaps' validity layout).
  std::vector<float> validity() const;
  // 1 where the estimate is a lower bound (bracketToCubeMap's still_clipped layout).
  std::vector<std::uint8_t> lowerBounds() const;

  // The stored state: the float RGBA texels, face-major (rgb, signed confidence).
  const std::vector<glm::vec4>& texels() const { return texels_; }
  // Restores saved texels; false (and nothing changed) when the size is
  // wrong or a value is non-finite or negative where it cannot be.
  bool restore(const std::vector<glm::vec4>& texels, std::string& error);

 private:
  ProbeAccumulatorSettings settings_;
  NoiseLookup noise_;
  std::vector<glm::vec4> texels_;
  std::vector<float> texel_solid_angle_sr_;  // by position on a face (the same on every face)
  long seen_texels_ = 0;
  // add()'s working storage, kept from view to view.
  std::vector<float> view_luminance_;
  std::vector<std::uint8_t> changed_, replace_;
  std::vector<std::size_t> open_;
};

}  // namespace probelight::ibl
