#include "ibl/spherical_blur.hpp"

#include <algorithm>
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

LatLongRGB::LatLongRGB(int width_px, int height_px)
    : width(width_px), height(height_px), texels(static_cast<size_t>(width_px) * height_px, glm::vec3(0.0f)) {}

glm::vec3 LatLongRGB::sampleBilinear(double theta_rad, double phi_rad) const {
  if (width <= 0 || height <= 0 || !std::isfinite(theta_rad) || !std::isfinite(phi_rad)) return glm::vec3(0.0f);
  theta_rad = std::fmod(theta_rad, 2.0 * M_PI);
  if (theta_rad < 0.0) theta_rad += 2.0 * M_PI;
  if (theta_rad > M_PI) {  // past the south pole, or (from below 0) past the north one
    theta_rad = 2.0 * M_PI - theta_rad;
    phi_rad += M_PI;
  }
  const double v = std::clamp(theta_rad / M_PI * height - 0.5, 0.0, height - 1.0);
  const double u = phi_rad / (2.0 * M_PI) * width - 0.5;
  const int y0 = std::min(static_cast<int>(v), height - 1);
  const int y1 = std::min(y0 + 1, height - 1);
  const double fy = v - y0;
  const double u_floor = std::floor(u);
  const double fx = u - u_floor;
  int x0 = static_cast<int>(std::fmod(u_floor, static_cast<double>(width)));
  if (x0 < 0) x0 += width;
  const int x1 = (x0 + 1) % width;
  const glm::dvec3 top = glm::mix(glm::dvec3(texel(x0, y0)), glm::dvec3(texel(x1, y0)), fx);
  const glm::dvec3 bottom = glm::mix(glm::dvec3(texel(x0, y1)), glm::dvec3(texel(x1, y1)), fx);
  return glm::vec3(glm::mix(top, bottom, fy));
}

double colatitudeRad(const glm::dvec3& direction) {
  // atan2 rather than acos(z / |d|): acos loses half the digits near the poles.
  return std::atan2(std::hypot(direction.x, direction.y), direction.z);
}

double azimuthRad(const glm::dvec3& direction) { return std::atan2(direction.y, direction.x); }

namespace {

struct CosineTaps {
  std::vector<double> angle_rad, weight;
  double weight_sum = 0.0;
  CosineTaps(int half_taps, BlurKernel kernel) {
    const SphericalBlurPass pass{BlurAxis::kEast, 0.0, half_taps, kernel};
    for (int i = -half_taps; i <= half_taps; ++i) {
      angle_rad.push_back(blurTapAngleRad(pass, i));
      weight.push_back(blurTapWeight(pass, angle_rad.back()));
      weight_sum += weight.back();
    }
  }
};

}  // namespace

LatLongRGB eastPassToLatLong(const CubeMapRGB& input, int rows, int half_taps) {
  LatLongRGB output(2 * rows, rows);
  const CosineTaps taps(half_taps, BlurKernel::kCosineSquared);
  for (int y = 0; y < output.height; ++y) {
    const double theta = (y + 0.5) * M_PI / output.height;
    for (int x = 0; x < output.width; ++x) {
      const double phi = (x + 0.5) * 2.0 * M_PI / output.width;
      const glm::dvec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      const glm::dvec3 east(-std::sin(phi), std::cos(phi), 0.0);  // cross(+Z, d) / sin(theta)
      glm::dvec3 sum(0.0);
      for (size_t k = 0; k < taps.weight.size(); ++k)
        sum += taps.weight[k] *
               glm::dvec3(input.sampleBilinear(std::cos(taps.angle_rad[k]) * d + std::sin(taps.angle_rad[k]) * east));
      output.texel(x, y) = glm::vec3(sum / taps.weight_sum);
    }
  }
  return output;
}

LatLongRGB northPassOnLatLong(const LatLongRGB& input) {
  const int rows = input.height;
  LatLongRGB output(input.width, rows);
  const int half_taps = rows / 2;
  std::vector<double> weight;
  double weight_sum = 0.0;
  for (int j = -half_taps; j <= half_taps; ++j) {
    weight.push_back(std::cos(j * M_PI / rows));
    weight_sum += weight.back();
  }
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < input.width; ++x) {
      glm::dvec3 sum(0.0);
      for (int j = -half_taps; j <= half_taps; ++j) {
        int row = y + j, column = x;
        if (row < 0 || row >= rows) {  // over a pole: the mirrored row of the opposite meridian
          row = row < 0 ? -row - 1 : 2 * rows - row - 1;
          column = (x + input.width / 2) % input.width;
        }
        sum += weight[static_cast<size_t>(j + half_taps)] * glm::dvec3(input.texel(column, row));
      }
      output.texel(x, y) = glm::vec3(sum / weight_sum);
    }
  }
  return output;
}

CubeMapRGB latLongToCube(const LatLongRGB& input, int face_size) {
  CubeMapRGB output(face_size);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < face_size; ++y)
      for (int x = 0; x < face_size; ++x) {
        const glm::dvec3 n = cubeTexelCenterDirection(face, x, y, face_size);
        output.texel(face, x, y) = input.sampleBilinear(colatitudeRad(n), azimuthRad(n));
      }
  return output;
}

CubeMapRGB irradianceOverPiByCosinePasses(const CubeMapRGB& radiance, const CosineIrradianceSettings& settings,
                                          const std::vector<float>* validity) {
  const ValidityWeightedCube prefiltered = prefilterWithValidity(radiance, validity, settings.prefilter_face_size);
  const auto north_of_east = [&](const CubeMapRGB& map) {
    return latLongToCube(northPassOnLatLong(eastPassToLatLong(map, settings.intermediate_rows, settings.half_taps)),
                         settings.output_face_size);
  };
  const CubeMapRGB premultiplied = north_of_east(prefiltered.premultiplied);
  const CubeMapRGB coverage = north_of_east(prefiltered.validity);
  CubeMapRGB output(settings.output_face_size);
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (size_t i = 0; i < output.faces[face].size(); ++i) {
      const double a = coverage.faces[face][i].r;
      // Normalised convolution; a footprint that saw nothing at all stays 0.
      output.faces[face][i] = a > 1e-6 ? glm::vec3(glm::dvec3(premultiplied.faces[face][i]) / a) : glm::vec3(0.0f);
    }
  }
  return output;
}

}  // namespace probelight::ibl
