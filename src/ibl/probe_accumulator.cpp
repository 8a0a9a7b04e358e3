#include "ibl/probe_accumulator.hpp"
#include "core/finite_vector.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace probelight::ibl {

namespace {

double lum(const glm::vec3& rgb) { return luminance(glm::dvec3(rgb)); }

// sqrt(a^2 + b^2) without std::hypot's care for overflow (sigmas are far
// from it) and its cost.
double quadratureSum(double a, double b) { return std::sqrt(a * a + b * b); }

// Texel (x, y) of `face`, or past its edge: the texel of the next face
// that the extended face plane's direction falls in.
std::size_t texelAt(int face, int x, int y, int n) {
  const std::size_t per_face = static_cast<std::size_t>(n) * n;
  if (x >= 0 && y >= 0 && x < n && y < n)
    return static_cast<std::size_t>(face) * per_face + static_cast<std::size_t>(y) * n + x;
  const CubeTexelCoord past{face, (x + 0.5) / n, (y + 0.5) / n};
  const CubeTexelCoord coord = directionToCubeCoord(cubeCoordToDirection(past));
  const int cx = std::clamp(static_cast<int>(coord.s * n), 0, n - 1);
  const int cy = std::clamp(static_cast<int>(coord.t * n), 0, n - 1);
  return static_cast<std::size_t>(coord.face) * per_face + static_cast<std::size_t>(cy) * n + cx;
}

}  // namespace

NoiseLookup::NoiseLookup(const SampleNoise& noise)
    : code_sigma_(noise.code_sigma),
      clip_level_(noise.clip_level),
      inverse_clip_level_(noise.clip_level > 0.0 ? 1.0 / noise.clip_level : 0.0) {
  const double reflectance = noise.probe_reflectance > 0.0 ? noise.probe_reflectance : 1.0;
  std::vector<double> decoded(256);  // code -> map units
  for (int code = 0; code < 256; ++code)
    decoded[static_cast<std::size_t>(code)] = decodeCameraValue(noise.camera_transfer, code / 255.0) / reflectance;
  // One code's worth of light at a level: the decode's step there.
  auto stepAt = [&](double level) {
    const auto above = std::upper_bound(decoded.begin(), decoded.end(), level);
    const std::size_t code = std::clamp<std::size_t>(static_cast<std::size_t>(above - decoded.begin()), 1, 255);
    return code_sigma_ * (decoded[code] - decoded[code - 1]);
  };
  sigma_by_bin_.resize(kBins + 1);
  for (int bin = 0; bin <= kBins; ++bin) {
    const double root = std::min(1.0, (bin + 0.5) / kBins);
    sigma_by_bin_[static_cast<std::size_t>(bin)] = stepAt(root * root * clip_level_);
  }
  smallest_sigma_ = *std::min_element(sigma_by_bin_.begin(), sigma_by_bin_.end());
  for (std::size_t code = 1; code < decoded.size(); ++code)
    smallest_sigma_ = std::min(smallest_sigma_, code_sigma_ * (decoded[code] - decoded[code - 1]));
  smallest_sigma_ = std::max(smallest_sigma_, 0.0);
}

double NoiseLookup::sigma(double luminance) const {
  if (!(clip_level_ > 0.0)) return sigma_by_bin_[0];
  const double level = luminance > 0.0 ? std::min(luminance, clip_level_) : 0.0;  // NaN: 0
  const int bin = std::min(kBins, static_cast<int>(std::sqrt(static_cast<float>(level * inverse_clip_level_)) * kBins));
  const double at_level = sigma_by_bin_[static_cast<std::size_t>(bin)];
  return luminance > clip_level_ ? at_level * luminance / clip_level_ : at_level;
}

ProbeObservation::ProbeObservation(int face_size)
    : radiance(face_size),
      confidence(static_cast<std::size_t>(kCubeFaceCount) * face_size * face_size, 0.0f),
      lower_bound(confidence.size(), 0),
      source(confidence.size(), 0) {}

void ProbeObservation::reset(int face_size) {
  const std::size_t count = static_cast<std::size_t>(kCubeFaceCount) * face_size * face_size;
  if (radiance.face_size != face_size) radiance = CubeMapRGB(face_size);
  for (auto& face : radiance.faces) std::fill(face.begin(), face.end(), glm::vec3(0.0f));
  confidence.assign(count, 0.0f);
  lower_bound.assign(count, 0);
  source.assign(count, 0);
}

ProbeAccumulator::ProbeAccumulator(ProbeAccumulatorSettings settings)
    : settings_(settings), noise_(settings.noise) {
  if (settings_.face_size < 1) throw std::invalid_argument("probe accumulator: face_size must be >= 1");
  if (!(settings_.memory_views >= 1.0) || !(settings_.change_sigmas > 0.0) || settings_.max_search_texels < 1)
    throw std::invalid_argument("probe accumulator: memory_views >= 1, change_sigmas > 0, max_search_texels >= 1");
  const int n = settings_.face_size;
  texel_solid_angle_sr_.resize(static_cast<std::size_t>(n) * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      texel_solid_angle_sr_[static_cast<std::size_t>(y) * n + x] = static_cast<float>(cubeTexelSolidAngle(x, y, n));
  clear();
}

void ProbeAccumulator::clear() {
  texels_.assign(static_cast<std::size_t>(kCubeFaceCount) * settings_.face_size * settings_.face_size,
                 glm::vec4(0.0f));
  seen_texels_ = 0;
}

void ProbeAccumulator::scaleRadiance(double factor) { scaleRadiance(glm::dvec3(factor)); }

void ProbeAccumulator::scaleRadiance(const glm::dvec3& factor_rgb) {
  for (int c = 0; c < 3; ++c)
    if (!(factor_rgb[c] > 0.0) || !std::isfinite(factor_rgb[c])) return;
  const glm::vec3 factor(factor_rgb);
  for (glm::vec4& texel : texels_) {
    texel.r *= factor.r;
    texel.g *= factor.g;
    texel.b *= factor.b;
  }
}

AccumulateCounts ProbeAccumulator::add(const ProbeObservation& view) {
  const int n = settings_.face_size;
  if (view.face_size() != n || view.texelCount() != texels_.size() || view.lower_bound.size() != texels_.size())
    throw std::invalid_argument("probe accumulator: an observation of face size " + std::to_string(view.face_size()) +
                                " given to a probe of " + std::to_string(n));
  const std::size_t per_face = static_cast<std::size_t>(n) * n;
  const double texel_angle_rad = 0.5 * std::numbers::pi / n;  // at the face centre, the largest
  const double decay = 1.0 - 1.0 / settings_.memory_views;
  const double k = settings_.change_sigmas;
  AccumulateCounts counts;

  // The full sweeps walk the faces in order (i = face * per_face + local)
  // rather than dividing each index by per_face.
  auto forEachSample = [&](auto&& fn) {
    std::size_t i = 0;
    for (const std::vector<glm::vec3>& face : view.radiance.faces)
      for (const glm::vec3& value : face) fn(i++, value);
  };
  // Per texel of the view: its luminance, NaN where the view did not see it.
  std::vector<float>& view_lum = view_luminance_;
  view_lum.resize(texels_.size());
  forEachSample([&](std::size_t i, const glm::vec3& value) {
    view_lum[i] = view.confidence[i] > 0.0f && allFinite(value) ? static_cast<float>(lum(value)) : NAN;
  });
  auto seenByView = [&](std::size_t i) { return !std::isnan(view_lum[i]); };
  // Texels each way the view's direction uncertainty spans (may exceed
  // max_search_texels: such a sample cannot seed a change).
  auto searchRadius = [&](std::size_t i) {
    const double sigma_rad = 1.0 / std::sqrt(static_cast<double>(view.confidence[i]));
    return std::max(1, static_cast<int>(std::ceil(std::min(sigma_rad / texel_angle_rad, 1e6))));
  };
  const double least_sigma = noise_.smallestSigma();

  // Pass 1: where the light changed. The view could have read, for texel i,
  // any of its own samples within its direction uncertainty; the estimate
  // outside all of them (beyond noise) is a change.
  std::vector<std::uint8_t>& changed = changed_;
  changed.assign(texels_.size(), 0);
  for (std::size_t i = 0; i < texels_.size(); ++i) {
    const glm::vec4& kept = texels_[i];
    if (!seenByView(i) || kept.a == 0.0f) continue;
    const double estimate = lum(glm::vec3(kept));
    const double own = view_lum[i];
    const bool kept_bound = kept.a < 0.0f;
    // The neighbourhood's range below holds the texel's own sample, and
    // every sigma is at least least_sigma: a sample within k times that
    // noise of the estimate passes all three tests below. Most texels of a
    // steady room stop here.
    const double sigma_estimate = noise_.sigma(estimate);
    const double least_noise_sq = k * k * (sigma_estimate * sigma_estimate + least_sigma * least_sigma);
    if ((own - estimate) * (own - estimate) <= least_noise_sq) continue;
    const int radius = searchRadius(i);
    // A view this unsure of the direction (a ball's rim) cannot tell a
    // change from its own smear at this resolution: it only merges.
    if (radius > settings_.max_search_texels) continue;
    const int face = static_cast<int>(i / per_face);
    const int x = static_cast<int>(i % per_face) % n, y = static_cast<int>(i % per_face) / n;
    float lo = INFINITY, hi = -INFINITY;
    bool bounded_above = true;
    // The tests below widen the estimate's own noise by the sample's, so a
    // neighbour within k of the estimate's sigma rules out "below" (one at
    // or under estimate + k sigma) or "above" (one at or over estimate - k
    // sigma) whatever the rest hold: once both are ruled out the scan
    // stops. Not for a bound estimate, whose test needs the whole range.
    const double rules_out_below = estimate + k * sigma_estimate;
    const double rules_out_above = estimate - k * sigma_estimate;
    bool may_be_below = true, may_be_above = !kept_bound;
    const bool may_stop = !kept_bound;
    auto include = [&](std::size_t j) {
      const float value = view_lum[j];
      if (std::isnan(value)) return false;
      lo = std::min(lo, value);
      hi = std::max(hi, value);
      if (view.lower_bound[j]) bounded_above = false;
      if (value <= rules_out_below) may_be_below = false;
      if (value >= rules_out_above || !bounded_above) may_be_above = false;
      return may_stop && !may_be_below && !may_be_above;
    };
    bool ruled_out = false;
    if (x >= radius && y >= radius && x + radius < n && y + radius < n) {
      for (int dy = -radius; dy <= radius && !ruled_out; ++dy) {
        const std::size_t row = i + static_cast<std::ptrdiff_t>(dy) * n;
        for (int dx = -radius; dx <= radius && !ruled_out; ++dx) ruled_out = include(row + dx);
      }
    } else {
      for (int dy = -radius; dy <= radius && !ruled_out; ++dy)
        for (int dx = -radius; dx <= radius && !ruled_out; ++dx) ruled_out = include(texelAt(face, x + dx, y + dy, n));
    }
    if (ruled_out) continue;
    const double noise = quadratureSum(sigma_estimate, noise_.sigma(lo));
    // A lower bound estimate says only "at least": only a view that reads
    // less than it, beyond noise, contradicts it.
    const bool below = estimate + k * noise < lo;
    const bool above =
        !kept_bound && bounded_above && estimate - k * quadratureSum(sigma_estimate, noise_.sigma(hi)) > hi;
    const bool bound_broken = kept_bound && !view.lower_bound[i] && own + k * noise < estimate;
    if (below || above || bound_broken) changed[i] = 1;
  }
  // A change is a connected region that differs from the estimate by
  // more than noise, one texel of which at least no misplaced direction
  // explains (pass 1): grown from those over 8-neighbours, so that a lamp
  // switched on appears whole, edges included, even to a view too unsure of
  // its directions for pass 1 to clear more than the lamp's core.
  std::vector<std::uint8_t>& replace = replace_;
  replace = changed;
  std::vector<std::size_t>& open = open_;
  open.clear();
  for (std::size_t i = 0; i < texels_.size(); ++i)
    if (changed[i]) open.push_back(i);
  while (!open.empty()) {
    const std::size_t i = open.back();
    open.pop_back();
    const int face = static_cast<int>(i / per_face);
    const int x = static_cast<int>(i % per_face) % n, y = static_cast<int>(i % per_face) / n;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const std::size_t j = texelAt(face, x + dx, y + dy, n);
        if (replace[j] || !seenByView(j) || texels_[j].a == 0.0f) continue;
        const double estimate = lum(glm::vec3(texels_[j])), value = view_lum[j];
        // A clipped sample says "at least": it differs only when above.
        const double difference = view.lower_bound[j] ? value - estimate : std::abs(value - estimate);
        if (!(difference > 0.0)) continue;
        // difference > k * quadratureSum(both sigmas), squared.
        const double sigma_estimate = noise_.sigma(estimate), sigma_value = noise_.sigma(value);
        if (difference * difference > k * k * (sigma_estimate * sigma_estimate + sigma_value * sigma_value)) {
          replace[j] = 1;
          open.push_back(j);
        }
      }
  }

  // Pass 2: the update.
  forEachSample([&](std::size_t i, const glm::vec3& value) {
    if (!seenByView(i)) return;
    ++counts.seen;
    glm::vec4& kept = texels_[i];
    const glm::vec3 x = glm::max(value, glm::vec3(0.0f));
    const float c = view.confidence[i];
    const bool x_bound = view.lower_bound[i] != 0;
    const double before = lum(glm::vec3(kept));
    const float signed_c = x_bound ? -c : c;
    if (kept.a == 0.0f) {
      kept = glm::vec4(x, signed_c);
      ++seen_texels_;
      ++counts.first;
      return;  // a texel seen for the first time is not a move of the maps' light: counted apart
    }
    const bool kept_bound = kept.a < 0.0f;
    const float kept_c = std::abs(kept.a);
    if (replace[i]) {
      kept = glm::vec4(x, signed_c);
      ++counts.changed;
    } else if (x_bound) {
      if (kept_bound || lum(x) > before) {
        // Two bounds: the tighter one holds. A bound above the estimate
        // (within noise, or pass 1 would have replaced it): raised to it.
        const glm::vec3 raised = glm::max(glm::vec3(kept), x);
        const bool rises = lum(raised) > before;
        kept = glm::vec4(raised, -static_cast<float>(decay * kept_c + c));
        ++(rises ? counts.raised : counts.kept);
      } else {
        ++counts.kept;  // a measurement above the bound already says more
      }
    } else if (kept_bound) {
      kept = glm::vec4(x, c);  // a measurement consistent with a bound replaces it
      ++counts.merged;
    } else {
      const double total = decay * kept_c + c;
      const float w = static_cast<float>(c / total);
      kept = glm::vec4(glm::vec3(kept) + w * (x - glm::vec3(kept)), static_cast<float>(total));
      ++counts.merged;
    }
    const double after = lum(glm::vec3(kept));
    // A division only for a move larger than the largest yet.
    const double move = std::abs(after - before);
    if (move > counts.largest_move_sigmas * least_sigma) {
      const double sigma = std::max(noise_.sigma(std::max(before, after)), 1e-12);
      counts.largest_move_sigmas = std::max(counts.largest_move_sigmas, move / sigma);
    }
  });
  return counts;
}

void ProbeAccumulator::demoteToLowerBound(std::size_t texel) {
  if (texel < texels_.size()) texels_[texel].a = -std::abs(texels_[texel].a);
}

double ProbeAccumulator::seenSolidAngleFraction() const {
  const int n = settings_.face_size;
  double seen = 0.0;
  for (std::size_t i = 0; i < texels_.size(); ++i)
    if (texels_[i].a != 0.0f) {
      const int local = static_cast<int>(i % (static_cast<std::size_t>(n) * n));
      seen += cubeTexelSolidAngle(local % n, local / n, n);
    }
  return seen / (4.0 * std::numbers::pi);
}

CubeMapRGB ProbeAccumulator::radianceMap(float clamp_level) const { return radianceMap(glm::vec3(clamp_level)); }

CubeMapRGB ProbeAccumulator::radianceMap(const glm::vec3& clamp_rgb) const {
  const int n = settings_.face_size;
  CubeMapRGB map(n);
  const std::size_t per_face = static_cast<std::size_t>(n) * n;
  for (std::size_t i = 0; i < texels_.size(); ++i)
    map.faces[i / per_face][i % per_face] = glm::min(glm::vec3(texels_[i]), clamp_rgb);
  return map;
}

std::vector<float> ProbeAccumulator::validity() const {
  std::vector<float> out(texels_.size());
  for (std::size_t i = 0; i < texels_.size(); ++i) out[i] = texels_[i].a != 0.0f ? 1.0f : 0.0f;
  return out;
}

std::vector<std::uint8_t> ProbeAccumulator::lowerBounds() const {
  std::vector<std::uint8_t> out(texels_.size());
  for (std::size_t i = 0; i < texels_.size(); ++i) out[i] = texels_[i].a < 0.0f ? 1 : 0;
  return out;
}

bool ProbeAccumulator::restore(const std::vector<glm::vec4>& texels, std::string& error) {
  if (texels.size() != texels_.size()) {
    error = "holds " + std::to_string(texels.size()) + " texels, a " + std::to_string(settings_.face_size) +
            "^2 cube has " + std::to_string(texels_.size());
    return false;
  }
  long seen = 0;
  for (std::size_t i = 0; i < texels.size(); ++i) {
    const glm::vec4& t = texels[i];
    if (!allFinite(glm::vec3(t)) || !std::isfinite(t.a) || t.r < 0.0f || t.g < 0.0f || t.b < 0.0f) {
      error = "texel " + std::to_string(i) + " is negative or not finite";
      return false;
    }
    if (t.a != 0.0f) ++seen;
  }
  texels_ = texels;
  seen_texels_ = seen;
  return true;
}

}  // namespace probelight::ibl
