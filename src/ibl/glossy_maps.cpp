#include "ibl/glossy_maps.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "ibl/spherical_blur.hpp"

namespace probelight::ibl {

GlossyLevelSettings defaultGlossyLevel(int level) {
  GlossyLevelSettings settings;
  if (level == 1) {
    settings.exponent = 16.0;
    settings.prefilter_face_size = 16;
    settings.intermediate_face_size = 32;
    settings.output_face_size = 16;
  }
  return settings;
}

double glossyTapAngleRad(double exponent, int half_taps, int i) {
  return half_taps > 0 && exponent > 0.0 ? i * 3.0 / (std::sqrt(exponent) * half_taps) : 0.0;
}

double glossyTapWeight(double power, double angle_rad) {
  const double a2 = angle_rad * angle_rad;
  const double s =
      a2 * (1.0 / 2.0 + a2 * (1.0 / 12.0 + a2 * (1.0 / 45.0 + a2 * (17.0 / 2520.0 + a2 * (31.0 / 14175.0)))));
  return std::exp(-power * s);
}

namespace {

struct Taps {
  std::vector<double> angle, cosine, sine, weight;
  double weight_sum = 0.0;
};

Taps makeTaps(double exponent, int half_taps, double power) {
  Taps taps;
  for (int i = -half_taps; i <= half_taps; ++i) {
    const double a = glossyTapAngleRad(exponent, half_taps, i);
    taps.angle.push_back(a);
    taps.cosine.push_back(std::cos(a));
    taps.sine.push_back(std::sin(a));
    taps.weight.push_back(glossyTapWeight(power, a));
    taps.weight_sum += taps.weight.back();
  }
  return taps;
}

// The east integral through d along tangent t: sum_i w_i cube(cos a_i d + sin a_i t) / sum w.
glm::dvec4 eastIntegral(const ValidityWeightedCube& cube, const Taps& taps, const glm::dvec3& d, const glm::dvec3& t) {
  glm::dvec4 sum(0.0);
  for (size_t i = 0; i < taps.angle.size(); ++i) sum += taps.weight[i] * cube.sample(taps.cosine[i] * d + taps.sine[i] * t);
  return sum / taps.weight_sum;
}

}  // namespace

CubeMapRGB glossyMap(const CubeMapRGB& radiance, const GlossyLevelSettings& settings,
                     const std::vector<float>* validity, std::vector<float>* coverage) {
  const ValidityWeightedCube prefiltered = prefilterWithValidity(radiance, validity, settings.prefilter_face_size);
  const Taps east = makeTaps(settings.exponent, settings.half_taps, settings.exponent + 1.0);
  const Taps north = makeTaps(settings.exponent, settings.half_taps, settings.exponent);

  const int m = settings.intermediate_face_size;
  ValidityWeightedCube intermediate{CubeMapRGB(m), CubeMapRGB(m)};
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < m; ++y) {
      for (int x = 0; x < m; ++x) {
        const glm::dvec3 p = cubeTexelCenterDirection(face, x, y, m);
        const glm::dvec4 v = eastIntegral(prefiltered, east, p, blurTangent(p, BlurAxis::kEast));
        intermediate.premultiplied.texel(face, x, y) = glm::vec3(glm::dvec3(v));
        intermediate.validity.texel(face, x, y) = glm::vec3(static_cast<float>(v.w));
      }
    }
  }

  const double pole_cosine = std::cos(settings.pole_direct_deg * M_PI / 180.0);
  const int n = settings.output_face_size;
  CubeMapRGB output(n);
  if (coverage) coverage->assign(static_cast<size_t>(kCubeFaceCount) * n * n, 0.0f);
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const glm::dvec3 r = cubeTexelCenterDirection(face, x, y, n);
        const glm::dvec3 east_tangent = blurTangent(r, BlurAxis::kEast);
        const glm::dvec3 north_tangent = blurTangent(r, BlurAxis::kNorth);
        glm::dvec4 sum(0.0);
        for (size_t j = 0; j < north.angle.size(); ++j) {
          const glm::dvec3 d = north.cosine[j] * r + north.sine[j] * north_tangent;
          // Near +-Z the intermediate texels were integrated along east
          // circles of every orientation; integrate this tap's own circle.
          const glm::dvec4 inner = std::abs(d.z) > pole_cosine ? eastIntegral(prefiltered, east, d, east_tangent)
                                                                : intermediate.sample(d);
          sum += north.weight[j] * inner;
        }
        sum /= north.weight_sum;
        // Normalised convolution; a footprint that saw nothing stays 0.
        output.texel(face, x, y) = sum.w > 1e-6 ? glm::vec3(glm::dvec3(sum) / sum.w) : glm::vec3(0.0f);
        if (coverage) (*coverage)[static_cast<size_t>(face) * n * n + static_cast<size_t>(y) * n + x] =
            static_cast<float>(std::max(sum.w, 0.0));
      }
    }
  }
  return output;
}

}  // namespace probelight::ibl
