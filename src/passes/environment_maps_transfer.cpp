// EnvironmentMaps' maps to and from the CPU: read back (tests, the truth
// monitor, the lighting fit, SH9's projection) and set from a CPU map (the
// benches and the GPU tests' inputs), in either storage.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "passes/environment_maps.hpp"
#include "passes/framebuffer_state_guard.hpp"
#include "ibl/color_transfer.hpp"

namespace probelight::passes {

namespace {

float halfToFloat(std::uint16_t half) {
  const std::uint32_t sign = (half >> 15) & 1u;
  const std::uint32_t exponent = (half >> 10) & 0x1Fu;
  const std::uint32_t mantissa = half & 0x3FFu;
  float magnitude;
  if (exponent == 0) {
    magnitude = std::ldexp(static_cast<float>(mantissa), -24);
  } else if (exponent == 31) {
    magnitude = mantissa == 0 ? INFINITY : NAN;
  } else {
    magnitude = std::ldexp(static_cast<float>(mantissa | 0x400u), static_cast<int>(exponent) - 25);
  }
  return sign ? -magnitude : magnitude;
}

std::uint16_t floatToHalf(float value) {
  // Round to nearest; the values stored are finite and non-negative linear light.
  std::uint32_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  const std::uint32_t sign = (bits >> 16) & 0x8000u;
  const int exponent = static_cast<int>((bits >> 23) & 0xFFu) - 127 + 15;
  std::uint32_t mantissa = bits & 0x7FFFFFu;
  if (exponent <= 0) {
    if (exponent < -10) return static_cast<std::uint16_t>(sign);
    mantissa |= 0x800000u;
    const int shift = 14 - exponent;
    std::uint32_t half_mantissa = mantissa >> shift;
    if ((mantissa >> (shift - 1)) & 1u) ++half_mantissa;
    return static_cast<std::uint16_t>(sign | half_mantissa);
  }
  if (exponent >= 31) return static_cast<std::uint16_t>(sign | 0x7C00u);
  std::uint32_t half = sign | (static_cast<std::uint32_t>(exponent) << 10) | (mantissa >> 13);
  if (mantissa & 0x1000u) ++half;  // carries into the exponent correctly
  return static_cast<std::uint16_t>(half);
}

}  // namespace

bool EnvironmentMaps::setReflection(const ibl::CubeMapRGB& reflection, std::string& error,
                                    const std::vector<float>* validity) {
  if (reflection.face_size != reflection_.face_size) {
    error = "EnvironmentMaps::setReflection: map has " + std::to_string(reflection.face_size) +
            " px faces, the reflection map is configured for " + std::to_string(reflection_.face_size);
    return false;
  }
  const size_t texel_count = static_cast<size_t>(reflection.face_size) * static_cast<size_t>(reflection.face_size);
  if (validity != nullptr && validity->size() != texel_count * ibl::kCubeFaceCount) {
    error = "EnvironmentMaps::setReflection: validity has " + std::to_string(validity->size()) + " values, expected " +
            std::to_string(texel_count * ibl::kCubeFaceCount);
    return false;
  }
  const auto alpha = [&](int face, size_t i) {
    return validity == nullptr ? 1.0f
                               : std::clamp((*validity)[static_cast<size_t>(face) * texel_count + i], 0.0f, 1.0f);
  };
  float brightest = 1.0f;
  for (const auto& face : reflection.faces) {
    for (const glm::vec3& texel : face) brightest = std::max({brightest, texel.r, texel.g, texel.b});
  }
  const float scale = storage_ == CubeStorage::kSrgb8 ? brightest : 1.0f;
  glBindTexture(GL_TEXTURE_CUBE_MAP, reflection_.texture.id());
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    const auto& texels = reflection.faces[static_cast<size_t>(face)];
    const GLenum target = GL_TEXTURE_CUBE_MAP_POSITIVE_X + static_cast<GLenum>(face);
    if (storage_ == CubeStorage::kSrgb8) {
      std::vector<std::uint8_t> bytes(texel_count * 4u);
      for (size_t i = 0; i < texel_count; ++i) {
        for (int c = 0; c < 3; ++c) {
          bytes[4 * i + static_cast<size_t>(c)] = ibl::linearToSrgbCode(static_cast<double>(texels[i][c]) / scale);
        }
        bytes[4 * i + 3] = static_cast<std::uint8_t>(std::lround(alpha(face, i) * 255.0f));
      }
      glTexSubImage2D(target, 0, 0, 0, reflection.face_size, reflection.face_size, GL_RGBA, GL_UNSIGNED_BYTE,
                      bytes.data());
    } else {
      std::vector<std::uint16_t> halves(texel_count * 4u);
      for (size_t i = 0; i < texel_count; ++i) {
        for (int c = 0; c < 3; ++c) halves[4 * i + static_cast<size_t>(c)] = floatToHalf(texels[i][c]);
        halves[4 * i + 3] = floatToHalf(alpha(face, i));
      }
      glTexSubImage2D(target, 0, 0, 0, reflection.face_size, reflection.face_size, GL_RGBA, texel_format_.type,
                      halves.data());
    }
  }
  reflection_.linear_scale = scale;
  return gles::checkGl("glTexSubImage2D(reflection cube)", error);
}

std::optional<ibl::CubeMapRGB> EnvironmentMaps::readCube(const GpuCubeMap& map, std::string& error,
                                                         std::vector<float>* validity) const {
  const int n = map.face_size;
  const size_t texel_count = static_cast<size_t>(n) * static_cast<size_t>(n);
  ibl::CubeMapRGB cube(n);
  if (validity != nullptr) validity->assign(texel_count * ibl::kCubeFaceCount, 0.0f);
  FramebufferStateGuard guard;
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  std::vector<float> rgba(texel_count * 4u);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X + static_cast<GLenum>(face),
                           map.texture.id(), 0);
    if (storage_ == CubeStorage::kSrgb8) {
      std::vector<std::uint8_t> bytes(texel_count * 4u);
      glReadPixels(0, 0, n, n, GL_RGBA, GL_UNSIGNED_BYTE, bytes.data());
      for (size_t i = 0; i < texel_count; ++i) {
        for (int c = 0; c < 3; ++c) {
          rgba[4 * i + static_cast<size_t>(c)] = static_cast<float>(
              ibl::srgbCodeToLinear(bytes[4 * i + static_cast<size_t>(c)]) * map.linear_scale);
        }
        rgba[4 * i + 3] = bytes[4 * i + 3] / 255.0f;
      }
    } else {
      // GLES2 guarantees only RGBA/UNSIGNED_BYTE plus one implementation
      // pair; float buffers offer RGBA/FLOAT (ES3) or RGBA/HALF_FLOAT.
      GLint read_type = 0;
      GLint read_format = 0;
      glGetIntegerv(GL_IMPLEMENTATION_COLOR_READ_TYPE, &read_type);
      glGetIntegerv(GL_IMPLEMENTATION_COLOR_READ_FORMAT, &read_format);
      if (read_format == GL_RGBA && (read_type == GL_HALF_FLOAT_OES || read_type == 0x140B /* GL_HALF_FLOAT */)) {
        std::vector<std::uint16_t> halves(texel_count * 4u);
        glReadPixels(0, 0, n, n, GL_RGBA, static_cast<GLenum>(read_type), halves.data());
        // Every 16-bit pattern decoded once: a read-back follows each map
        // update while clipped lights are followed, and ldexp per channel
        // cost more than the read itself.
        static const std::vector<float> kHalfToFloat = [] {
          std::vector<float> table(65536);
          for (std::uint32_t h = 0; h < table.size(); ++h) table[h] = halfToFloat(static_cast<std::uint16_t>(h));
          return table;
        }();
        for (size_t i = 0; i < halves.size(); ++i) rgba[i] = kHalfToFloat[halves[i]];
      } else {
        glReadPixels(0, 0, n, n, GL_RGBA, GL_FLOAT, rgba.data());
      }
    }
    if (!gles::checkGl("glReadPixels(cube face)", error)) {
      error += "; this GPU cannot read back its half-float cube maps (run with 8-bit maps to inspect them)";
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X, 0, 0);
      return std::nullopt;
    }
    auto& texels = cube.faces[static_cast<size_t>(face)];
    for (size_t i = 0; i < texel_count; ++i) {
      texels[i] = glm::vec3(rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]);
      if (validity != nullptr) (*validity)[static_cast<size_t>(face) * texel_count + i] = rgba[4 * i + 3];
    }
  }
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X, 0, 0);
  return cube;
}

std::optional<ibl::CubeMapRGB> EnvironmentMaps::readReflection(std::string& error, std::vector<float>* validity) const {
  return readCube(reflection_, error, validity);
}
std::optional<ibl::CubeMapRGB> EnvironmentMaps::readPrefiltered(std::string& error,
                                                                std::vector<float>* validity) const {
  return readCube(prefiltered_, error, validity);
}
std::optional<ibl::CubeMapRGB> EnvironmentMaps::readDiffuse(std::string& error, std::vector<float>* validity) const {
  return readCube(diffuse_, error, validity);
}
std::optional<ibl::CubeMapRGB> EnvironmentMaps::readGlossy(int level, std::string& error,
                                                           std::vector<float>* validity) const {
  if (level < 0 || level >= settings_.glossy_levels) {
    error = "EnvironmentMaps::readGlossy: level " + std::to_string(level) + " of " +
            std::to_string(settings_.glossy_levels);
    return std::nullopt;
  }
  return readCube(glossy_[static_cast<size_t>(level)].map, error, validity);
}

}  // namespace probelight::passes
