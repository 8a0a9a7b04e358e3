#include "ibl/spherical_blur.hpp"

#include <cmath>
#include <vector>

namespace probelight::ibl {

glm::dvec3 blurTangent(const glm::dvec3& n, BlurAxis axis) {
  const glm::dvec3 across_meridian = glm::cross(glm::dvec3(0.0, 0.0, 1.0), n);
  // At the poles "east" is undefined; any fixed tangent will do there.
  const glm::dvec3 east =
      glm::length(across_meridian) < 1e-4 ? glm::dvec3(1.0, 0.0, 0.0) : glm::normalize(across_meridian);
  return axis == BlurAxis::kEast ? east : glm::cross(n, east);
}

double blurTapAngleRad(const SphericalBlurPass& pass, int i) {
  if (pass.kernel == BlurKernel::kGaussian)
    return pass.half_taps > 0 ? i * 3.0 * pass.sigma_rad / pass.half_taps : 0.0;
  return i * M_PI / (2.0 * pass.half_taps + 1.0);
}

double blurTapWeight(const SphericalBlurPass& pass, double angle_rad) {
  switch (pass.kernel) {
    case BlurKernel::kCosineSquared:
      return std::cos(angle_rad) * std::cos(angle_rad);
    case BlurKernel::kCosine:
      return std::cos(angle_rad);
    case BlurKernel::kGaussian:
      break;
  }
  return pass.sigma_rad > 0.0 ? std::exp(-angle_rad * angle_rad / (2.0 * pass.sigma_rad * pass.sigma_rad))
                              : (angle_rad == 0.0 ? 1.0 : 0.0);
}

CubeMapRGB sphericalBlurPass(const CubeMapRGB& input, int output_face_size, const SphericalBlurPass& pass) {
  CubeMapRGB output(output_face_size);
  const int tap_count = 2 * pass.half_taps + 1;
  std::vector<double> angle_rad(tap_count);
  std::vector<double> weight(tap_count);
  double weight_sum = 0.0;
  for (int k = 0; k < tap_count; ++k) {
    angle_rad[k] = blurTapAngleRad(pass, k - pass.half_taps);
    weight[k] = blurTapWeight(pass, angle_rad[k]);
    weight_sum += weight[k];
  }
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < output_face_size; ++y) {
      for (int x = 0; x < output_face_size; ++x) {
        const glm::dvec3 n = cubeTexelCenterDirection(face, x, y, output_face_size);
        const glm::dvec3 t = blurTangent(n, pass.axis);
        glm::dvec3 sum(0.0);
        for (int k = 0; k < tap_count; ++k) {
          const glm::dvec3 direction = std::cos(angle_rad[k]) * n + std::sin(angle_rad[k]) * t;
          sum += weight[k] * glm::dvec3(input.sampleBilinear(direction));
        }
        output.texel(face, x, y) = glm::vec3(sum / weight_sum);
      }
    }
  }
  return output;
}

CubeMapRGB downsampleCubeMap(const CubeMapRGB& input, int factor) {
  if (factor <= 1 || input.face_size % factor != 0) return input;
  const int output_size = input.face_size / factor;
  CubeMapRGB output(output_size);
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < output_size; ++y) {
      for (int x = 0; x < output_size; ++x) {
        glm::dvec3 sum(0.0);
        double solid_angle_sum = 0.0;
        for (int dy = 0; dy < factor; ++dy) {
          for (int dx = 0; dx < factor; ++dx) {
            const int sx = x * factor + dx, sy = y * factor + dy;
            const double solid_angle = cubeTexelSolidAngle(sx, sy, input.face_size);
            sum += solid_angle * glm::dvec3(input.texel(face, sx, sy));
            solid_angle_sum += solid_angle;
          }
        }
        output.texel(face, x, y) = glm::vec3(sum / solid_angle_sum);
      }
    }
  }
  return output;
}

glm::dvec4 ValidityWeightedCube::sample(const glm::dvec3& direction) const {
  return glm::dvec4(glm::dvec3(premultiplied.sampleBilinear(direction)), validity.sampleBilinear(direction).r);
}

ValidityWeightedCube prefilterWithValidity(const CubeMapRGB& radiance, const std::vector<float>* validity,
                                           int prefilter_face_size) {
  ValidityWeightedCube source{radiance, CubeMapRGB(radiance.face_size)};
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (size_t i = 0; i < radiance.faces[face].size(); ++i) {
      const float weight = validity ? (*validity)[face * radiance.faces[face].size() + i] : 1.0f;
      source.premultiplied.faces[face][i] = radiance.faces[face][i] * weight;
      source.validity.faces[face][i] = glm::vec3(weight);
    }
  }
  const int factor = prefilter_face_size > 0 ? radiance.face_size / prefilter_face_size : 1;
  return {downsampleCubeMap(source.premultiplied, factor), downsampleCubeMap(source.validity, factor)};
}

namespace {

// One cosine pass over (premultiplied radiance, validity).
ValidityWeightedCube weightedPass(const ValidityWeightedCube& input, int output_face_size, const SphericalBlurPass& pass) {
  return {sphericalBlurPass(input.premultiplied, output_face_size, pass),
          sphericalBlurPass(input.validity, output_face_size, pass)};
}

}  // namespace

CubeMapRGB irradianceOverPiByCosinePasses(const CubeMapRGB& radiance, const CosineIrradianceSettings& settings,
                                          const std::vector<float>* validity) {
  const ValidityWeightedCube prefiltered = prefilterWithValidity(radiance, validity, settings.prefilter_face_size);

  const SphericalBlurPass east{BlurAxis::kEast, 0.0, settings.half_taps, BlurKernel::kCosineSquared};
  const SphericalBlurPass north{BlurAxis::kNorth, 0.0, settings.half_taps, BlurKernel::kCosine};
  const ValidityWeightedCube intermediate = weightedPass(prefiltered, settings.intermediate_face_size, east);

  const int tap_count = 2 * settings.half_taps + 1;
  std::vector<double> east_angle(tap_count), east_weight(tap_count), north_angle(tap_count), north_weight(tap_count);
  for (int k = 0; k < tap_count; ++k) {
    east_angle[k] = blurTapAngleRad(east, k - settings.half_taps);
    east_weight[k] = blurTapWeight(east, east_angle[k]);
    north_angle[k] = blurTapAngleRad(north, k - settings.half_taps);
    north_weight[k] = blurTapWeight(north, north_angle[k]);
  }
  double east_weight_sum = 0.0;
  for (double w : east_weight) east_weight_sum += w;
  const double pole_cosine = std::cos(settings.pole_direct_deg * M_PI / 180.0);

  CubeMapRGB output(settings.output_face_size);
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < settings.output_face_size; ++y) {
      for (int x = 0; x < settings.output_face_size; ++x) {
        const glm::dvec3 n = cubeTexelCenterDirection(face, x, y, settings.output_face_size);
        const glm::dvec3 east_tangent = blurTangent(n, BlurAxis::kEast);
        const glm::dvec3 north_tangent = blurTangent(n, BlurAxis::kNorth);
        glm::dvec4 sum(0.0);
        double weight_sum = 0.0;
        for (int j = 0; j < tap_count; ++j) {
          const glm::dvec3 d = std::cos(north_angle[j]) * n + std::sin(north_angle[j]) * north_tangent;
          glm::dvec4 inner(0.0);
          if (std::abs(d.z) > pole_cosine) {
            for (int i = 0; i < tap_count; ++i)
              inner += east_weight[i] *
                       prefiltered.sample(std::cos(east_angle[i]) * d + std::sin(east_angle[i]) * east_tangent);
            inner /= east_weight_sum;
          } else {
            inner = intermediate.sample(d);
          }
          sum += north_weight[j] * inner;
          weight_sum += north_weight[j];
        }
        sum /= weight_sum;
        // Normalised convolution; a footprint that saw nothing at all stays 0.
        output.texel(face, x, y) = sum.w > 1e-6 ? glm::vec3(glm::dvec3(sum) / sum.w) : glm::vec3(0.0f);
      }
    }
  }
  return output;
}

}  // namespace probelight::ibl
