#include "passes/camera_response.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <glm/gtc/type_ptr.hpp>

namespace probelight::passes {

std::string cameraTransferDefines(const ibl::CameraTransfer& transfer) {
  switch (transfer.curve) {
    case ibl::CameraTransfer::Curve::kGamma: return "#define CAMERA_TRANSFER_GAMMA\n";
    case ibl::CameraTransfer::Curve::kLinear: return "#define CAMERA_TRANSFER_LINEAR\n";
    case ibl::CameraTransfer::Curve::kSrgb: break;
  }
  return "";
}

std::string cameraResponseDefines(const ibl::CameraTransfer& transfer, bool match_noise) {
  return cameraTransferDefines(transfer) + (match_noise ? "#define MATCH_SENSOR_NOISE\n" : "");
}

std::string bloomBrightPassDefines() {
  return "#define BLOOM_BRIGHT_PASS\n#define BLOOM_RANGE " + std::to_string(kBloomRange) + "\n";
}

std::vector<std::uint8_t> standardNormalTexels(int size_px, std::uint32_t seed) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<std::uint8_t> texels(static_cast<size_t>(size_px) * static_cast<size_t>(size_px) * 4u);
  for (size_t i = 0; i < texels.size(); ++i) {
    if (i % 4 == 3) {
      texels[i] = 255;
      continue;
    }
    texels[i] = static_cast<std::uint8_t>(std::clamp(std::floor(128.0 + 32.0 * normal(generator)), 0.0, 255.0));
  }
  return texels;
}

bool SensorNoiseTexture::init(std::string& error) {
  const std::vector<std::uint8_t> texels = standardNormalTexels(kSizePx, 20081215u);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  auto texture = gles::createTexture2D(kSizePx, kSizePx, GL_RGBA, GL_UNSIGNED_BYTE, GL_NEAREST, texels.data(), error);
  if (!texture) return false;
  texture_ = std::move(*texture);
  // A power-of-two size: GLES2 core repeats it, one texel a pixel across the frame.
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
  glBindTexture(GL_TEXTURE_2D, 0);
  return gles::checkGl("SensorNoiseTexture::init", error);
}

glm::vec2 noiseOffsetForFrame(std::uint64_t frame_index, int size_px) {
  // splitmix64's finaliser: every bit of the index moves every bit out.
  std::uint64_t z = frame_index + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  const auto size = static_cast<std::uint64_t>(std::max(size_px, 1));
  return glm::vec2(static_cast<float>(z % size), static_cast<float>((z >> 32) % size)) / static_cast<float>(size);
}

void setCameraResponseUniforms(const gles::Program& program, const ibl::CameraTransfer& transfer,
                               const glm::vec3& response_gain_rgb, const SensorNoiseMatch* noise,
                               const SensorNoiseTexture& texture, int unit) {
  glUniform3fv(program.uniform("u_response_gain_rgb"), 1, glm::value_ptr(response_gain_rgb));
  if (transfer.curve == ibl::CameraTransfer::Curve::kGamma)
    glUniform1f(program.uniform("u_camera_gamma"), static_cast<float>(transfer.gamma));
  if (noise == nullptr) return;
  glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(unit));
  glBindTexture(GL_TEXTURE_2D, texture.id());
  glUniform1i(program.uniform("u_noise_normal"), unit);
  const glm::vec2 offset = noiseOffsetForFrame(noise->frame_index, SensorNoiseTexture::kSizePx);
  glUniform2fv(program.uniform("u_noise_offset"), 1, glm::value_ptr(offset));
  const glm::vec3 dark(noise->model.dark_code), bright(noise->model.bright_code);
  const glm::vec3 dark_sigma(noise->model.dark_sigma_code), bright_sigma(noise->model.bright_sigma_code);
  glUniform3fv(program.uniform("u_noise_dark_code"), 1, glm::value_ptr(dark));
  glUniform3fv(program.uniform("u_noise_bright_code"), 1, glm::value_ptr(bright));
  glUniform3fv(program.uniform("u_noise_dark_sigma_code"), 1, glm::value_ptr(dark_sigma));
  glUniform3fv(program.uniform("u_noise_bright_sigma_code"), 1, glm::value_ptr(bright_sigma));
}

}  // namespace probelight::passes
