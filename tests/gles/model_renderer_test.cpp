// A glTF model on the GPU (passes/model_renderer) against the CPU reference
// ibl::shadeMetallicRoughness, with the maps the GPU read (read back); the
// alpha modes, the 16-bit index split and the texture paths; the corpus.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gles/render_target.hpp"
#include "gles_test_support.hpp"
#include "ibl/camera_projection.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/metallic_roughness.hpp"
#include "ibl/near_floor.hpp"
#include "model/gltf_loader.hpp"
#include "model/model_placement.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "passes/ground_shadow.hpp"
#include "passes/model_renderer.hpp"
#include "passes/object_compositor.hpp"

namespace probelight {
namespace {

using test::GpuTest;

constexpr double kHalfWidthM = 0.08;
constexpr double kHeightM = 0.16;
constexpr int kTexturePx = 16;  // 4 x 4 blocks of 4 x 4 texels
constexpr int kBlockPx = 4;

// The colour of block (bx, by) of the test texture, sRGB bytes.
glm::u8vec4 blockColor(int bx, int by) {
  return {static_cast<std::uint8_t>(40 + 60 * bx), static_cast<std::uint8_t>(220 - 50 * by),
          static_cast<std::uint8_t>(90 + 30 * ((bx + by) % 3)), 255};
}

// A vertical square in the plane y = 0 facing -y (toward the camera), u
// along +x and v down the square (glTF's UV origin is the image's top left).
model::MeshModel texturedQuad(const model::Material& material, bool with_texture, std::uint8_t alpha_left = 255) {
  model::MeshModel quad;
  model::Primitive p;
  const auto w = static_cast<float>(kHalfWidthM), h = static_cast<float>(kHeightM);
  p.positions_m = {{-w, 0, 0}, {w, 0, 0}, {w, 0, h}, {-w, 0, h}};
  p.normals = {{0, -1, 0}, {0, -1, 0}, {0, -1, 0}, {0, -1, 0}};
  p.uv0 = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
  p.indices = {0, 1, 2, 0, 2, 3};
  p.material = 0;
  quad.primitives.push_back(p);
  quad.materials.push_back(material);
  if (with_texture) {
    model::TextureImage image;
    image.name = "blocks";
    image.width = image.height = kTexturePx;
    for (int y = 0; y < kTexturePx; ++y)
      for (int x = 0; x < kTexturePx; ++x) {
        glm::u8vec4 c = blockColor(x / kBlockPx, y / kBlockPx);
        if (x < kTexturePx / 2) c.a = alpha_left;
        image.rgba.insert(image.rgba.end(), {c.r, c.g, c.b, c.a});
      }
    quad.images.push_back(image);
  }
  quad.min_m = {-w, 0, 0};
  quad.max_m = {w, 0, h};
  return quad;
}

struct ModelStage {
  CameraIntrinsics camera = test::testCamera();
  PoseCamFromWorld pose = test::lookAt({0.03, -0.32, 0.12}, {0.0, 0.0, 0.08});
  gles::RenderTarget target;
  passes::CameraFrameTexture frame;
  passes::EnvironmentMaps maps;
  passes::ObjectCompositor compositor;
  std::optional<ibl::CubeMapRGB> diffuse, reflection;
  std::vector<ibl::CubeMapRGB> glossy_maps;
  // As the CPU reference takes them: the glossy maps read back, and the
  // ladder's rung alphas for the maps' glossy levels.
  std::vector<const ibl::CubeMapRGB*> glossy;
  std::vector<double> rung_alphas;
};

void initStage(ModelStage& stage, const gles::Capabilities& caps) {
  std::string error;
  ASSERT_TRUE(stage.target.init(stage.camera.width_px, stage.camera.height_px, error)) << error;
  ASSERT_TRUE(stage.frame.init(caps, error)) << error;
  ASSERT_TRUE(stage.maps.init(caps, {}, error)) << error;
  ASSERT_TRUE(stage.compositor.init(caps, {}, stage.maps.storage(), error)) << error;
  ibl::CubeMapRGB environment(stage.maps.settings().reflection_face_size);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (int y = 0; y < environment.face_size; ++y)
      for (int x = 0; x < environment.face_size; ++x)
        environment.texel(face, x, y) =
            glm::vec3(test::analyticEnvironment(ibl::cubeTexelCenterDirection(face, x, y, environment.face_size)));
  ASSERT_TRUE(stage.maps.setReflection(environment, error)) << error;
  ASSERT_TRUE(stage.maps.updateDiffuse(error)) << error;
  ASSERT_TRUE(stage.maps.updateGlossy(error)) << error;
  stage.diffuse = stage.maps.readDiffuse(error);
  ASSERT_TRUE(stage.diffuse) << error;
  stage.reflection = stage.maps.readReflection(error);
  ASSERT_TRUE(stage.reflection) << error;
  for (int level = 0; level < stage.maps.glossyLevels(); ++level) {
    const auto glossy = stage.maps.readGlossy(level, error);
    ASSERT_TRUE(glossy) << error;
    stage.glossy_maps.push_back(*glossy);
  }
  for (const auto& map : stage.glossy_maps) stage.glossy.push_back(&map);
  const std::vector<double> exponents(stage.maps.settings().glossy_exponent.begin(),
                                      stage.maps.settings().glossy_exponent.begin() + stage.maps.glossyLevels());
  stage.rung_alphas = ibl::specularRungAlphas(exponents);
  ImageRGB8 grey;
  grey.resize(stage.camera.width_px, stage.camera.height_px);
  std::fill(grey.pixels.begin(), grey.pixels.end(), 90);
  ASSERT_TRUE(stage.frame.upload(grey, error)) << error;
}

bool renderModel(ModelStage& stage, passes::ModelRenderer& renderer, ImageRGB8& result, std::string& error) {
  stage.target.bind();
  stage.compositor.drawCameraBackground(stage.frame);
  if (!renderer.draw(stage.camera, stage.pose, ibl::SceneLighting{}, stage.maps, error)) return false;
  return stage.target.readRGB(result, error);
}

// Where pixel (x, y)'s calibrated ray meets the quad's plane: (u, v), or
// nothing off the quad.
std::optional<glm::dvec2> quadUvAt(const ModelStage& stage, int x, int y) {
  const glm::dvec3 eye = stage.pose.cameraCenterWorld();
  const glm::dvec3 ray =
      glm::normalize(glm::transpose(stage.pose.R_cam_from_world) * ibl::pixelToCameraRay(stage.camera, {x, y}));
  if (!(ray.y > 0.0)) return std::nullopt;
  const glm::dvec3 hit = eye + (-eye.y / ray.y) * ray;
  const glm::dvec2 uv((hit.x + kHalfWidthM) / (2 * kHalfWidthM), 1.0 - hit.z / kHeightM);
  if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0) return std::nullopt;
  return uv;
}

// Away from the block edges by a texel, bilinear filtering returns the
// block's own colour: the texel is known exactly.
std::optional<glm::u8vec4> blockAt(const glm::dvec2& uv) {
  const glm::dvec2 texel = uv * double(kTexturePx);
  const glm::dvec2 within = texel - glm::floor(texel / double(kBlockPx)) * double(kBlockPx);
  if (within.x < 1.0 || within.x > kBlockPx - 1.0 || within.y < 1.0 || within.y > kBlockPx - 1.0) return std::nullopt;
  return blockColor(static_cast<int>(texel.x) / kBlockPx, static_cast<int>(texel.y) / kBlockPx);
}

struct ShadingCase {
  const char* name;
  glm::vec4 base_color_factor;
  float metallic, roughness;
  bool textured;
};

class ModelShadingTest : public GpuTest, public ::testing::WithParamInterface<bool> {};

// Every pixel of the quad's interior (and off the texture's block edges)
// against the CPU reference at that pixel's ray. The quad is flat, so its
// normal is exact and so is the view direction: the budget is the output's
// rounding (0.5 level), fp32 arithmetic, and the GPU's bilinear weights in
// the 48x48 8-bit BRDF table, which llvmpipe (and boards) quantise to 8 bits
// of a texel: the table moves by at most 3 codes a texel, so 3/256 of a code.
// 1.5 levels bounds them all; a wrong ladder rung, a missed sRGB decode or a
// Fresnel term left out moves pixels by many levels (checked below).
TEST_P(ModelShadingTest, MatchesCpuShadeMetallicRoughness) {
  const bool force_8bit = GetParam();
  const gles::Capabilities caps =
      force_8bit ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities();
  ModelStage stage;
  ASSERT_NO_FATAL_FAILURE(initStage(stage, caps));
  const std::vector<const ibl::CubeMapRGB*>& glossy = stage.glossy;
  const std::vector<double>& rung_alphas = stage.rung_alphas;
  const ibl::EnvironmentBrdfTable table;

  const ShadingCase cases[] = {
      {"textured dielectric, rough", {1, 1, 1, 1}, 0.0f, 1.0f, true},
      {"textured dielectric, roughness 0.6", {1, 1, 1, 1}, 0.0f, 0.6f, true},
      {"gold, roughness 0.3", {1.0f, 0.77f, 0.34f, 1}, 1.0f, 0.3f, false},
      {"steel, roughness 0.05", {0.56f, 0.57f, 0.58f, 1}, 1.0f, 0.05f, false},
  };
  for (const ShadingCase& c : cases) {
    model::Material material;
    material.name = c.name;
    material.base_color_factor = c.base_color_factor;
    material.metallic_factor = c.metallic;
    material.roughness_factor = c.roughness;
    if (c.textured) material.base_color.image = 0;
    const model::MeshModel quad = texturedQuad(material, c.textured);
    passes::ModelRenderer renderer;
    std::string error;
    ASSERT_TRUE(renderer.init(caps, stage.maps.storage(), quad, glm::dmat4(1.0), {}, error)) << error;
    ImageRGB8 result;
    ASSERT_TRUE(renderModel(stage, renderer, result, error)) << error;

    int compared = 0;
    double max_error = 0.0, max_error_if_wrong = 0.0;
    for (int y = 0; y < result.height; ++y)
      for (int x = 0; x < result.width; ++x) {
        const auto uv = quadUvAt(stage, x, y);
        // Half a pixel inside the edges at least: about 0.004 of the quad.
        if (!uv || uv->x < 0.01 || uv->x > 0.99 || uv->y < 0.01 || uv->y > 0.99) continue;
        glm::vec3 base(c.base_color_factor);
        if (c.textured) {
          const auto block = blockAt(*uv);
          if (!block) continue;
          base *= glm::vec3(ibl::srgbToLinear(block->r / 255.0f), ibl::srgbToLinear(block->g / 255.0f),
                            ibl::srgbToLinear(block->b / 255.0f));
        }
        ibl::MetallicRoughnessSurface surface;
        surface.base_color = base;
        surface.metallic = c.metallic;
        surface.roughness = c.roughness;
        const glm::dvec3 ray = glm::normalize(glm::transpose(stage.pose.R_cam_from_world) *
                                              ibl::pixelToCameraRay(stage.camera, {x, y}));
        const glm::vec3 to_eye(-ray);
        const glm::vec3 linear = ibl::shadeMetallicRoughness({0, -1, 0}, to_eye, surface, *stage.diffuse,
                                                             *stage.reflection, glossy, rung_alphas, table, {});
        // What a renderer a little wrong would give: the texture's bytes
        // taken as linear (no sRGB decode), or a metal's metallic misread
        // as 0.5 (the channel read from the wrong place, or lost).
        ibl::MetallicRoughnessSurface wrong = surface;
        if (c.textured) {
          const auto block = blockAt(*uv);
          wrong.base_color = glm::vec3(c.base_color_factor) * glm::vec3(*block) / 255.0f;
        } else {
          wrong.metallic = 0.5f;
        }
        const glm::vec3 naive = ibl::shadeMetallicRoughness({0, -1, 0}, to_eye, wrong, *stage.diffuse,
                                                            *stage.reflection, glossy, rung_alphas, table, {});
        for (int k = 0; k < 3; ++k) {
          const double expected = 255.0 * ibl::linearToSrgb(std::clamp(linear[k], 0.0f, 1.0f));
          const double gpu = result.row(y)[3 * x + k];
          max_error = std::max(max_error, std::abs(gpu - expected));
          max_error_if_wrong = std::max(
              max_error_if_wrong, std::abs(255.0 * ibl::linearToSrgb(std::clamp(naive[k], 0.0f, 1.0f)) - expected));
        }
        ++compared;
      }
    std::printf("[ measure  ] model shading (%s maps, %s): %d px, max |GPU-CPU| %.2f levels (a little wrong: %.1f)\n",
                stage.maps.storageDescription().c_str(), c.name, compared, max_error, max_error_if_wrong);
    EXPECT_GT(compared, 3000) << c.name;
    EXPECT_LE(max_error, 1.5) << c.name;
    EXPECT_GT(max_error_if_wrong, 3.0) << c.name << ": the comparison must tell a small mistake apart";
  }
}

INSTANTIATE_TEST_SUITE_P(Storage, ModelShadingTest, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "EightBitPath" : "BestPath"; });

// The floor beside the model in its reflections (ibl/near_floor.hpp): the
// quad's lower half reflects the ground in front of it, where a sphere's
// shadow lies, and which the camera's frame (a colour ramp here) shows.
// The GPU against the CPU reference with the same lookup, the ground
// texture's fractions (read back, filtered bilinearly as GL's LINEAR does)
// and the frame's bytes (filtered, then decoded, as the shader samples
// them), within the shading test's 1.5 levels; and the reference without
// the near floor is many levels off, so the check can tell.
//
// The camera has no lens distortion here: the GPU distorts a mesh's
// vertices and rasterises straight between them, so inside this quad's two
// large triangles a distorted view puts each pixel's surface point up to a
// pixel from the exact ray's, which the reflection carries to the ground
// several times over (2 mm at the quad's foot), across the shadow's edge.
TEST_F(GpuTest, NearFloorReflectionsMatchTheCpuReference) {
  const gles::Capabilities caps = test::sharedCapabilities();
  ModelStage stage;
  stage.camera.distortion = {};
  ASSERT_NO_FATAL_FAILURE(initStage(stage, caps));
  const std::vector<const ibl::CubeMapRGB*>& glossy = stage.glossy;
  const std::vector<double>& rung_alphas = stage.rung_alphas;
  const ibl::EnvironmentBrdfTable table;
  std::string error;

  ibl::ShadowCaster caster;
  caster.position_w = {0.0, -0.07};
  caster.radius_m = 0.03;
  ibl::ShadowLight light;
  light.direction_w = glm::normalize(glm::dvec3(0.0, -0.3, 1.0));
  light.share_rgb = glm::dvec3(0.7);
  light.rgb = glm::dvec3(1.0);
  light.cone_radius_rad = 0.05;
  passes::GroundShadow shadow;
  ASSERT_TRUE(shadow.init(caps, {}, error)) << error;
  ASSERT_TRUE(shadow.update({light}, caster, error)) << error;
  ASSERT_TRUE(shadow.hasShadow());
  const std::optional<std::vector<glm::vec3>> fractions = shadow.readFraction(error);
  ASSERT_TRUE(fractions) << error;
  const int n = shadow.groundTextureSizePx();
  const ibl::GroundRegion region = shadow.region();
  auto fractionAt = [&](const glm::vec2& ground_w) {
    const glm::dvec2 uv = (glm::dvec2(ground_w) - region.centre_w) / (2.0 * region.half_size_m) + 0.5;
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0) return glm::vec3(1.0f);
    const glm::dvec2 texel = uv * static_cast<double>(n) - 0.5;
    const int i0 = static_cast<int>(std::floor(texel.x)), j0 = static_cast<int>(std::floor(texel.y));
    const auto fx = static_cast<float>(texel.x - i0), fy = static_cast<float>(texel.y - j0);
    auto at = [&](int i, int j) {
      return (*fractions)[static_cast<size_t>(std::clamp(j, 0, n - 1)) * n + static_cast<size_t>(std::clamp(i, 0, n - 1))];
    };
    return glm::mix(glm::mix(at(i0, j0), at(i0 + 1, j0), fx), glm::mix(at(i0, j0 + 1), at(i0 + 1, j0 + 1), fx), fy);
  };

  // The frame: red across, green down.
  ImageRGB8 ramp;
  ramp.resize(stage.camera.width_px, stage.camera.height_px);
  for (int y = 0; y < ramp.height; ++y)
    for (int x = 0; x < ramp.width; ++x) {
      std::uint8_t* p = ramp.row(y) + 3 * x;
      p[0] = static_cast<std::uint8_t>(40 + 200 * x / ramp.width);
      p[1] = static_cast<std::uint8_t>(30 + 200 * y / ramp.height);
      p[2] = 120;
    }
  ASSERT_TRUE(stage.frame.upload(ramp, error)) << error;
  auto cameraFloorAt = [&](const glm::vec3& ground_w) {
    const glm::dvec3 p = stage.pose.toCamera(glm::dvec3(ground_w));
    if (!(p.z > 1e-3) || (p.x * p.x + p.y * p.y) / (p.z * p.z) > ibl::cameraFloorReach2(stage.camera))
      return glm::vec4(0.0f);
    const glm::dvec2 pixel = ibl::projectToPixel(stage.camera, p);
    const float weight = ibl::cameraFloorWeight(glm::vec2(pixel), ramp.width, ramp.height);
    const double fx = std::clamp(pixel.x, 0.0, ramp.width - 1.0), fy = std::clamp(pixel.y, 0.0, ramp.height - 1.0);
    const int x0 = std::min(static_cast<int>(fx), ramp.width - 2), y0 = std::min(static_cast<int>(fy), ramp.height - 2);
    const double u = fx - x0, v = fy - y0;
    glm::vec4 seen(0.0f, 0.0f, 0.0f, weight);
    for (int k = 0; k < 3; ++k) {
      auto at = [&](int x, int y) { return ramp.row(y)[3 * x + k] / 255.0; };
      const double byte = (1 - v) * ((1 - u) * at(x0, y0) + u * at(x0 + 1, y0)) + v * ((1 - u) * at(x0, y0 + 1) + u * at(x0 + 1, y0 + 1));
      seen[k] = static_cast<float>(ibl::srgbToLinear(byte));
    }
    return seen;
  };

  ibl::NearFloorBall ball;
  ball.centre_w = {0.12f, -0.10f, 0.09f};
  ball.radius_m = 0.03f;
  ball.to_eye_w = glm::normalize(glm::vec3(stage.pose.cameraCenterWorld()) - ball.centre_w);
  for (const ShadingCase& c : {ShadingCase{"steel, roughness 0.05", {0.56f, 0.57f, 0.58f, 1}, 1.0f, 0.05f, false},
                               ShadingCase{"gold, roughness 0.3", {1.0f, 0.77f, 0.34f, 1}, 1.0f, 0.3f, false}}) {
    model::Material material;
    material.base_color_factor = c.base_color_factor;
    material.metallic_factor = c.metallic;
    material.roughness_factor = c.roughness;
    const model::MeshModel quad = texturedQuad(material, false);
    passes::ModelRenderer renderer;
    ASSERT_TRUE(renderer.init(caps, stage.maps.storage(), quad, glm::dmat4(1.0), {}, error)) << error;
    passes::ModelRenderer::NearFloor settings;
    settings.enabled = true;
    settings.ball_centre_w = glm::dvec3(ball.centre_w);
    settings.ball_radius_m = ball.radius_m;
    settings.shadow = &shadow;
    settings.camera_frame = &stage.frame;
    renderer.setNearFloor(settings);
    ImageRGB8 result;
    ASSERT_TRUE(renderModel(stage, renderer, result, error)) << error;
    const glm::dvec3 eye = stage.pose.cameraCenterWorld();
    int compared = 0, shadowed = 0;
    double max_error = 0.0, max_error_without = 0.0;
    for (int y = 0; y < result.height; ++y)
      for (int x = 0; x < result.width; ++x) {
        const auto uv = quadUvAt(stage, x, y);
        if (!uv || uv->x < 0.01 || uv->x > 0.99 || uv->y < 0.01 || uv->y > 0.99) continue;
        const glm::dvec3 ray = glm::normalize(glm::transpose(stage.pose.R_cam_from_world) *
                                              ibl::pixelToCameraRay(stage.camera, {x, y}));
        const glm::vec3 to_eye(-ray);
        const glm::vec3 r = glm::reflect(-to_eye, glm::vec3(0, -1, 0));
        if (!(r.z < -0.05f)) continue;  // the floor, clear of the horizon's seam of rungs
        ibl::MetallicRoughnessSurface surface;
        surface.base_color = glm::vec3(c.base_color_factor);
        surface.metallic = c.metallic;
        surface.roughness = c.roughness;
        ibl::NearFloorShading near_floor;
        near_floor.point_w = glm::vec3(eye + (-eye.y / ray.y) * ray);
        near_floor.ball = ball;
        near_floor.fraction = fractionAt;
        near_floor.camera_floor = cameraFloorAt;
        const glm::vec3 linear = ibl::shadeMetallicRoughness({0, -1, 0}, to_eye, surface, *stage.diffuse,
                                                             *stage.reflection, glossy, rung_alphas, table, {},
                                                             &near_floor);
        const glm::vec3 without = ibl::shadeMetallicRoughness({0, -1, 0}, to_eye, surface, *stage.diffuse,
                                                              *stage.reflection, glossy, rung_alphas, table, {});
        const ibl::NearFloorLookup lookup = ibl::nearFloorLookup(near_floor.point_w, r, ball);
        // Off the shadow's edge by a texel: there the fraction steps by
        // most of its range within a texel, and a lookup a hair away (the
        // GPU's 8-bit filter weights) reads another value.
        const glm::vec2 ground(lookup.ground_point_w);
        const float texel_m = static_cast<float>(2.0 * region.half_size_m / n);
        float lowest = 1.0f, highest = 0.0f;
        for (const glm::vec2& step : {glm::vec2(0.0f), glm::vec2(texel_m, 0.0f), glm::vec2(-texel_m, 0.0f),
                                      glm::vec2(0.0f, texel_m), glm::vec2(0.0f, -texel_m)}) {
          lowest = std::min(lowest, fractionAt(ground + 1.5f * step).r);
          highest = std::max(highest, fractionAt(ground + 1.5f * step).r);
        }
        if (highest - lowest > 0.02f) continue;
        shadowed += fractionAt(ground).r < 0.9f ? 1 : 0;
        for (int k = 0; k < 3; ++k) {
          const double expected = 255.0 * ibl::linearToSrgb(std::clamp(linear[k], 0.0f, 1.0f));
          max_error = std::max(max_error, std::abs(result.row(y)[3 * x + k] - expected));
          max_error_without = std::max(
              max_error_without, std::abs(255.0 * ibl::linearToSrgb(std::clamp(without[k], 0.0f, 1.0f)) - expected));
        }
        ++compared;
      }
    std::printf("[ measure  ] near floor (%s): %d px off the shadow's edge (%d reflect the shadow), max |GPU-CPU| "
                "%.2f levels (without the near floor: %.1f)\n",
                c.name, compared, shadowed, max_error, max_error_without);
    EXPECT_GT(compared, 1000) << c.name;
    EXPECT_GT(shadowed, 100) << c.name;
    EXPECT_LE(max_error, 1.5) << c.name;
    EXPECT_GT(max_error_without, 10.0) << c.name;
  }
}

// MASK: texels under the cutoff are not drawn at all (the background stays
// byte for byte), those above are opaque. BLEND: alpha 128 mixes the lit
// colour and the background in sRGB bytes, within 1 level of 8-bit blending.
TEST_F(GpuTest, AlphaMaskDiscardsAndBlendMixesWithTheVideo) {
  ModelStage stage;
  ASSERT_NO_FATAL_FAILURE(initStage(stage, test::sharedCapabilities()));
  std::string error;
  model::Material opaque;
  opaque.metallic_factor = 0.0f;
  opaque.base_color.image = 0;
  passes::ModelRenderer reference_renderer;
  ASSERT_TRUE(reference_renderer.init(test::sharedCapabilities(), stage.maps.storage(), texturedQuad(opaque, true),
                                      glm::dmat4(1.0), {}, error))
      << error;
  ImageRGB8 lit;
  ASSERT_TRUE(renderModel(stage, reference_renderer, lit, error)) << error;

  for (const model::AlphaMode mode : {model::AlphaMode::kMask, model::AlphaMode::kBlend}) {
    model::Material material = opaque;
    material.alpha_mode = mode;
    const std::uint8_t alpha_left = mode == model::AlphaMode::kMask ? 100 : 128;  // under the cutoff 0.5 for MASK
    passes::ModelRenderer renderer;
    ASSERT_TRUE(renderer.init(test::sharedCapabilities(), stage.maps.storage(), texturedQuad(material, true, alpha_left),
                              glm::dmat4(1.0), {}, error))
        << error;
    ImageRGB8 result;
    ASSERT_TRUE(renderModel(stage, renderer, result, error)) << error;
    int left = 0, right = 0;
    double max_left_error = 0.0, max_right_error = 0.0;
    for (int y = 0; y < result.height; ++y)
      for (int x = 0; x < result.width; ++x) {
        const auto uv = quadUvAt(stage, x, y);
        // A texel (1/16) and more from the edges and the middle: REPEAT's
        // bilinear reads mix the far side's alpha in at the quad's edges.
        if (!uv || uv->y < 0.07 || uv->y > 0.93 || uv->x < 0.07 || uv->x > 0.93 || std::abs(uv->x - 0.5) < 0.08) continue;
        for (int k = 0; k < 3; ++k) {
          const double gpu = result.row(y)[3 * x + k], shaded = lit.row(y)[3 * x + k];
          if (uv->x < 0.5) {
            const double expected = mode == model::AlphaMode::kMask ? 90.0 : (128.0 * shaded + 127.0 * 90.0) / 255.0;
            max_left_error = std::max(max_left_error, std::abs(gpu - expected));
          } else {
            max_right_error = std::max(max_right_error, std::abs(gpu - shaded));
          }
        }
        (uv->x < 0.5 ? left : right)++;
      }
    EXPECT_GT(left, 3000);
    EXPECT_GT(right, 3000);
    EXPECT_LE(max_left_error, mode == model::AlphaMode::kMask ? 0.0 : 1.0) << static_cast<int>(mode);
    EXPECT_EQ(max_right_error, 0.0) << static_cast<int>(mode);
  }
}

// A grid of 300 x 300 quads (90,601 vertices): beyond 16-bit indices. Cut
// into pieces (as a board without OES_element_index_uint needs) it must
// rasterise to the very same pixels as one 32-bit draw.
TEST_F(GpuTest, ModelsBeyondSixteenBitIndicesDrawTheSameWhenSplit) {
  const gles::Capabilities& caps = test::sharedCapabilities();
  if (!caps.element_index_uint) GTEST_SKIP() << "no OES_element_index_uint to compare the split with";
  ModelStage stage;
  ASSERT_NO_FATAL_FAILURE(initStage(stage, caps));
  model::MeshModel grid;
  model::Primitive p;
  const int n = 300;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      // A wavy sheet, so the shading differs from triangle to triangle.
      const float x = -0.08f + 0.16f * i / n, z = 0.16f * j / n;
      const float y = 0.01f * std::sin(40.0f * x) * std::cos(30.0f * z);
      p.positions_m.push_back({x, y, z});
      p.normals.push_back(glm::normalize(glm::vec3(-0.4f * std::cos(40.0f * x) * std::cos(30.0f * z), -1.0f,
                                                   0.3f * std::sin(40.0f * x) * std::sin(30.0f * z))));
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const auto a = static_cast<std::uint32_t>(j * (n + 1) + i), b = a + 1, c = a + n + 1, d = c + 1;
      p.indices.insert(p.indices.end(), {a, b, d, a, d, c});
    }
  grid.primitives.push_back(p);
  grid.materials.push_back(model::Material{});
  grid.materials[0].roughness_factor = 0.2f;
  std::string error;
  ImageRGB8 whole, split;
  passes::ModelRenderer one_draw;
  ASSERT_TRUE(one_draw.init(caps, stage.maps.storage(), grid, glm::dmat4(1.0), {}, error)) << error;
  EXPECT_FALSE(one_draw.stats().short_indices_only);
  ASSERT_TRUE(renderModel(stage, one_draw, whole, error)) << error;
  passes::ModelRendererSettings settings;
  settings.force_short_indices = true;
  passes::ModelRenderer pieces;
  ASSERT_TRUE(pieces.init(caps, stage.maps.storage(), grid, glm::dmat4(1.0), settings, error)) << error;
  EXPECT_GE(pieces.stats().split_pieces, 2u);
  EXPECT_TRUE(pieces.stats().short_indices_only);
  ASSERT_TRUE(renderModel(stage, pieces, split, error)) << error;
  int differing = 0, covered = 0;
  for (std::size_t i = 0; i < whole.pixels.size(); ++i) {
    differing += whole.pixels[i] != split.pixels[i];
    covered += whole.pixels[i] != 90;
  }
  EXPECT_GT(covered, 20000);
  EXPECT_EQ(differing, 0);
}

// A one-primitive grey (0.8, dielectric) model of `p`, standing in the box
// [-half, half]^2 x [0, height], and its triangles as the shadow caster.
struct GreyMesh {
  model::MeshModel model;
  ibl::ShadowCaster caster;
};
GreyMesh greyMesh(model::Primitive p, float half_m, float height_m) {
  GreyMesh mesh;
  mesh.caster.shape = ibl::ShadowCaster::Shape::kMesh;
  auto triangles = std::make_shared<std::vector<glm::vec3>>();
  for (std::uint32_t index : p.indices) triangles->push_back(p.positions_m[index]);
  mesh.caster.mesh_triangles_w = triangles;
  mesh.caster.mesh_centre_w = {0.0, 0.0, 0.5 * height_m};
  mesh.caster.mesh_radius_m = glm::length(glm::dvec3(half_m, half_m, 0.5 * height_m));
  p.material = 0;
  mesh.model.primitives.push_back(std::move(p));
  mesh.model.materials.emplace_back();
  mesh.model.materials[0].metallic_factor = 0.0f;
  mesh.model.materials[0].base_color_factor = {0.8f, 0.8f, 0.8f, 1.0f};
  mesh.model.min_m = {-half_m, -half_m, 0.0f};
  mesh.model.max_m = {half_m, half_m, height_m};
  return mesh;
}

// Maps of a world of uniform radiance (above the horizon and below), and
// the diffuse map read back.
constexpr glm::vec3 kUniformRadiance(0.3f, 0.28f, 0.25f);
std::optional<ibl::CubeMapRGB> setUniformWorld(ModelStage& stage, std::string& error) {
  ibl::CubeMapRGB world(stage.maps.settings().reflection_face_size);
  for (auto& face : world.faces) std::fill(face.begin(), face.end(), kUniformRadiance);
  if (!stage.maps.setReflection(world, error) || !stage.maps.updateDiffuse(error)) return std::nullopt;
  return stage.maps.readDiffuse(error);
}

// One dome light straight above, of irradiance C = 0.4 pi L under a sky of radiance L.
ibl::ShadowLight overheadLight(const glm::vec3& sky_radiance) {
  ibl::ShadowLight light;
  light.direction_w = {0.0, 0.0, 1.0};
  light.rgb = glm::dvec3(0.4 * 3.14159265358979 * glm::dvec3(sky_radiance));
  light.share_rgb = glm::dvec3(0.4);
  light.cone_radius_rad = 0.01;
  return light;
}

// Self-shadowing: a table (a 16 cm floor plate and an 8 cm roof 6 cm above
// it, both facing up) under a uniform sky L and one dome light straight
// above of irradiance C = 0.4 pi L. The floor under the roof loses that
// light: its lit colour is scaled by 1 - C / (pi D) = 0.6 (D = L, the
// diffuse map of a uniform sky), lifted by the light the table bounces
// onto itself (ibl::multiBounceVisibility at its albedo, 0.8 + 0.04:
// 0.88), and the floor outside the roof's footprint and the roof itself
// keep all of it. Pixels within 3 map texels
// (2 mm) of the footprint's edge are left out; elsewhere the budget is the
// 8-bit output (1 level) on both renders. Both packed and depth-texture maps.
TEST_F(GpuTest, AModelShadowsItselfFromTheDomeLights) {
  const gles::Capabilities& caps = test::sharedCapabilities();
  for (const bool packed : {false, true}) {
    ModelStage stage;
    stage.pose = test::lookAt({0.02, -0.22, 0.26}, {0.0, 0.0, 0.0});
    ASSERT_NO_FATAL_FAILURE(initStage(stage, caps));
    std::string error;
    const auto diffuse = setUniformWorld(stage, error);
    ASSERT_TRUE(diffuse) << error;
    const glm::vec3 d_up = diffuse->sampleBilinear({0.0, 0.0, 1.0});

    model::Primitive p;
    const float floor_half = 0.08f, roof_half = 0.04f, roof_z = 0.06f;
    for (const auto& [half, z] : {std::pair{floor_half, 0.0f}, {roof_half, roof_z}}) {
      const auto base = static_cast<std::uint32_t>(p.positions_m.size());
      p.positions_m.insert(p.positions_m.end(), {{-half, -half, z}, {half, -half, z}, {half, half, z}, {-half, half, z}});
      p.normals.insert(p.normals.end(), 4, glm::vec3(0, 0, 1));
      p.indices.insert(p.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
    const GreyMesh mesh = greyMesh(p, floor_half, roof_z);
    const model::MeshModel& table = mesh.model;
    const ibl::ShadowCaster& caster = mesh.caster;
    const ibl::ShadowLight light = overheadLight(d_up);
    passes::GroundShadowSettings shadow_settings;
    shadow_settings.self_shadow_maps = true;
    shadow_settings.force_packed_depth = packed;
    passes::GroundShadow shadow;
    ASSERT_TRUE(shadow.init(caps, shadow_settings, error)) << error;
    ASSERT_TRUE(shadow.update({light}, caster, error)) << error;
    ASSERT_EQ(shadow.selfShadowLights().size(), 1u);

    passes::ModelRenderer renderer;
    ASSERT_TRUE(renderer.init(caps, stage.maps.storage(), table, glm::dmat4(1.0), {}, error)) << error;
    ImageRGB8 unshadowed, shadowed;
    ASSERT_TRUE(renderModel(stage, renderer, unshadowed, error)) << error;
    EXPECT_EQ(renderer.selfShadowLightsRead(), 0);
    renderer.setSelfShadow(&shadow.selfShadowLights(), shadow.shadowMapSizePx(), shadow.packedDepth());
    ASSERT_TRUE(renderModel(stage, renderer, shadowed, error)) << error;
    EXPECT_EQ(renderer.selfShadowLightsRead(), 1);

    const double expected_visibility = ibl::multiBounceVisibility(glm::vec3(1.0f - 0.4f), glm::vec3(0.84f)).r;
    EXPECT_NEAR(expected_visibility, 0.882, 0.001);
    const double margin_m = 3.0 * (2.0 * caster.mesh_radius_m * 1.1) / shadow.shadowMapSizePx();
    const glm::dvec3 eye = stage.pose.cameraCenterWorld();
    int under = 0, outside = 0, roof = 0;
    double worst_under = 0.0, worst_outside = 0.0;
    for (int y = 0; y < shadowed.height; ++y)
      for (int x = 0; x < shadowed.width; ++x) {
        const glm::dvec3 ray = glm::normalize(glm::transpose(stage.pose.R_cam_from_world) *
                                              ibl::pixelToCameraRay(stage.camera, {x, y}));
        if (!(ray.z < 0.0)) continue;
        // The roof first (it is nearer the camera where both lie on the ray).
        const glm::dvec3 on_roof = eye + ((roof_z - eye.z) / ray.z) * ray;
        const bool hits_roof = std::abs(on_roof.x) < roof_half && std::abs(on_roof.y) < roof_half;
        const glm::dvec3 on_floor = eye + (-eye.z / ray.z) * ray;
        const double inset = std::min(roof_half - std::abs(on_roof.x), roof_half - std::abs(on_roof.y));
        if (std::abs(inset) < 0.005) continue;  // the roof's edge in the image
        double visibility = 1.0;
        int* count = nullptr;
        double* worst = nullptr;
        if (hits_roof) {
          count = &roof;
          worst = &worst_outside;
        } else {
          const double floor_edge = std::min(floor_half - std::abs(on_floor.x), floor_half - std::abs(on_floor.y));
          if (floor_edge < 0.005) continue;
          const double footprint = std::min(roof_half - std::abs(on_floor.x), roof_half - std::abs(on_floor.y));
          if (std::abs(footprint) < margin_m) continue;
          visibility = footprint > 0.0 ? expected_visibility : 1.0;
          count = footprint > 0.0 ? &under : &outside;
          worst = footprint > 0.0 ? &worst_under : &worst_outside;
        }
        for (int k = 0; k < 3; ++k) {
          const double lit = ibl::srgbToLinear(unshadowed.row(y)[3 * x + k] / 255.0);
          const double expected = 255.0 * ibl::linearToSrgb(visibility * lit);
          *worst = std::max(*worst, std::abs(shadowed.row(y)[3 * x + k] - expected));
        }
        ++*count;
      }
    std::printf("[ measure  ] self-shadow (%s): under the roof %d px, max error %.2f levels; lit %d + %d px, %.2f\n",
                shadow.depthStorageDescription().c_str(), under, worst_under, outside, roof, worst_outside);
    EXPECT_GT(under, 500);
    EXPECT_GT(outside, 2000);
    EXPECT_GT(roof, 2000);
    // One level for each 8-bit render, plus the unshadowed level's own rounding scaled by 0.88.
    EXPECT_LE(worst_under, 1.5) << packed;
    EXPECT_LE(worst_outside, 0.0) << packed << ": a lit surface shadows itself (acne)";
  }
}

// The floor's light, which no dome light carries, hidden where the model
// stands between a point and the floor: an open box (an 8 cm floor plate
// and four 4 cm walls, each a pair of faces 2 mm apart, inward and
// outward) under a uniform world L, above and below, and one dome light
// straight above that no wall faces. A wall's face receives half its light
// from the floor, E_down (1 - n.z) / 2 = pi L / 2 of pi D = pi L. Inside,
// the walls see the box's own floor below them: the floor's half is
// hidden, visibility 0.5, lifted by the bounce (ibl::multiBounceVisibility
// at 0.84); outside they see the real floor: all of it kept. Against the
// same box drawn with the dome's self-shadow alone (the floor's light
// never hidden), per pixel, faces 3 map texels from the box's edges and
// corners left out.
TEST_F(GpuTest, AModelHidesTheFloorsLightFromItself) {
  const gles::Capabilities& caps = test::sharedCapabilities();
  ModelStage stage;
  stage.pose = test::lookAt({0.03, -0.24, 0.20}, {0.0, 0.0, 0.02});
  ASSERT_NO_FATAL_FAILURE(initStage(stage, caps));
  std::string error;
  const auto diffuse = setUniformWorld(stage, error);
  ASSERT_TRUE(diffuse) << error;

  constexpr float kHalf = 0.04f, kHeight = 0.04f, kWall = 0.002f;
  model::Primitive p;
  auto quad = [&](const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const glm::vec3& d, const glm::vec3& n) {
    const auto base = static_cast<std::uint32_t>(p.positions_m.size());
    p.positions_m.insert(p.positions_m.end(), {a, b, c, d});
    p.normals.insert(p.normals.end(), 4, n);
    // Wound counter-clockwise seen from n's side.
    const bool ccw = glm::dot(glm::cross(b - a, c - a), n) > 0.0f;
    if (ccw)
      p.indices.insert(p.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    else
      p.indices.insert(p.indices.end(), {base, base + 2, base + 1, base, base + 3, base + 2});
  };
  quad({-kHalf, -kHalf, 0}, {kHalf, -kHalf, 0}, {kHalf, kHalf, 0}, {-kHalf, kHalf, 0}, {0, 0, 1});
  for (int side = 0; side < 4; ++side) {
    const float angle = side * 0.5f * 3.14159265f;
    const glm::vec3 out(std::cos(angle), std::sin(angle), 0.0f), along(-out.y, out.x, 0.0f);
    for (const float offset : {kHalf - kWall, kHalf}) {
      const glm::vec3 centre = offset * out;
      const glm::vec3 n = offset < kHalf ? -out : out;
      quad(centre - kHalf * along, centre + kHalf * along, centre + kHalf * along + glm::vec3(0, 0, kHeight),
           centre - kHalf * along + glm::vec3(0, 0, kHeight), n);
    }
  }
  const GreyMesh mesh = greyMesh(p, kHalf, kHeight);
  const model::MeshModel& box = mesh.model;
  const ibl::ShadowCaster& caster = mesh.caster;
  const ibl::ShadowLight light = overheadLight(kUniformRadiance);
  passes::GroundShadowSettings shadow_settings;
  shadow_settings.self_shadow_maps = true;
  passes::GroundShadow shadow;
  ASSERT_TRUE(shadow.init(caps, shadow_settings, error)) << error;
  ASSERT_TRUE(shadow.update({light}, caster, error)) << error;
  ASSERT_EQ(shadow.floorSelfShadows().size(), static_cast<std::size_t>(passes::GroundShadow::kFloorLightCount));

  passes::ModelRenderer renderer;
  ASSERT_TRUE(renderer.init(caps, stage.maps.storage(), box, glm::dmat4(1.0), {}, error)) << error;
  ImageRGB8 dome_only, with_floor;
  renderer.setSelfShadow(&shadow.selfShadowLights(), shadow.shadowMapSizePx(), shadow.packedDepth());
  ASSERT_TRUE(renderModel(stage, renderer, dome_only, error)) << error;
  renderer.setSelfShadow(&shadow.selfShadowLights(), shadow.shadowMapSizePx(), shadow.packedDepth(),
                         &shadow.floorSelfShadows());
  ASSERT_TRUE(renderModel(stage, renderer, with_floor, error)) << error;

  const double d_side = diffuse->sampleBilinear({0.0, -1.0, 0.0}).r, d_down = diffuse->sampleBilinear({0.0, 0.0, -1.0}).r;
  const double inside_visibility =
      ibl::multiBounceVisibility(glm::vec3(static_cast<float>(1.0 - 0.5 * d_down / d_side)), glm::vec3(0.84f)).r;
  const double margin_m = 3.0 * (2.0 * caster.mesh_radius_m * 1.1) / shadow.shadowMapSizePx();
  const glm::dvec3 eye = stage.pose.cameraCenterWorld();
  int inner = 0, outer = 0;
  double worst_inner = 0.0, worst_outer = 0.0;
  for (int y = 0; y < with_floor.height; ++y)
    for (int x = 0; x < with_floor.width; ++x) {
      const glm::dvec3 ray = glm::normalize(glm::transpose(stage.pose.R_cam_from_world) *
                                            ibl::pixelToCameraRay(stage.camera, {x, y}));
      // The far wall's inner face (y = kHalf - kWall, facing -y) and the
      // near wall's outer face (y = -kHalf, facing -y): the camera looks
      // along +y at both.
      if (!(ray.y > 0.0)) continue;
      auto onPlaneY = [&](double plane_y) { return eye + ((plane_y - eye.y) / ray.y) * ray; };
      const glm::dvec3 near_outer = onPlaneY(-kHalf), far_inner = onPlaneY(kHalf - kWall);
      auto inFace = [&](const glm::dvec3& q) {
        return std::abs(q.x) < kHalf - kWall - margin_m && q.z > margin_m && q.z < kHeight - margin_m;
      };
      double visibility = 0.0;
      if (inFace(near_outer)) {
        visibility = 1.0;
        ++outer;
      } else if (inFace(far_inner)) {
        // Seen over the near wall, not through it.
        const glm::dvec3 over_near = onPlaneY(-kHalf + kWall);
        if (over_near.z < kHeight + margin_m) continue;
        visibility = inside_visibility;
        ++inner;
      } else {
        continue;
      }
      double& worst = visibility < 1.0 ? worst_inner : worst_outer;
      for (int k = 0; k < 3; ++k) {
        const double lit = ibl::srgbToLinear(dome_only.row(y)[3 * x + k] / 255.0);
        const double expected = 255.0 * ibl::linearToSrgb(visibility * lit);
        worst = std::max(worst, std::abs(with_floor.row(y)[3 * x + k] - expected));
      }
    }
  std::printf("[ measure  ] floor's light: inner walls %d px (visibility %.3f), max error %.2f levels; outer walls %d px, "
              "%.2f\n",
              inner, inside_visibility, worst_inner, outer, worst_outer);
  EXPECT_GT(inner, 300);
  EXPECT_GT(outer, 300);
  EXPECT_LT(inside_visibility, 0.9) << "the floor's share must show";
  EXPECT_LE(worst_inner, 1.5);
  EXPECT_LE(worst_outer, 0.0) << "a face that sees the floor lost its light";
}

TEST(ModelTextures, TextureTransformIsTranslationTimesRotationTimesScale) {
  model::TextureSlot slot;
  slot.uv_offset = {0.5f, 0.25f};
  slot.uv_rotation_rad = 0.5f * 3.14159265f;
  slot.uv_scale = {2.0f, 3.0f};
  // KHR_texture_transform's example order: scale (1, 0) -> (2, 0); rotate by
  // its matrix [cos sin; -sin cos] -> (0, -2); translate -> (0.5, -1.75).
  const glm::vec3 uv = passes::textureTransformMatrix(slot) * glm::vec3(1.0f, 0.0f, 1.0f);
  EXPECT_NEAR(uv.x, 0.5f, 1e-6f);
  EXPECT_NEAR(uv.y, -1.75f, 1e-6f);
  EXPECT_EQ(passes::textureTransformMatrix(model::TextureSlot{}), glm::mat3(1.0f));
}

TEST(ModelTextures, PowersOfTwoAreTheNearestInRatioWithinTheLimit) {
  EXPECT_EQ(passes::nearestPowerOfTwo(256, 2048), 256);
  EXPECT_EQ(passes::nearestPowerOfTwo(300, 2048), 256);  // 300 / 256 < 512 / 300
  EXPECT_EQ(passes::nearestPowerOfTwo(400, 2048), 512);
  EXPECT_EQ(passes::nearestPowerOfTwo(5000, 2048), 2048);
  EXPECT_EQ(passes::nearestPowerOfTwo(1, 2048), 1);
  EXPECT_EQ(passes::nearestPowerOfTwo(0, 2048), 1);
}

TEST(ModelTextures, RoughnessRangeSpansTheTexturesGreenChannelTimesTheFactor) {
  model::MeshModel model;
  model::TextureImage image;
  image.width = 2;
  image.height = 1;
  image.rgba = {0, 51, 0, 255, 0, 204, 0, 255};  // G 0.2 and 0.8
  model.images.push_back(image);
  model::Material material;
  material.roughness_factor = 0.5f;
  EXPECT_EQ(passes::materialRoughnessRange(material, model), std::make_pair(0.5f, 0.5f));
  material.metallic_roughness.image = 0;
  const auto [lo, hi] = passes::materialRoughnessRange(material, model);
  EXPECT_NEAR(lo, 0.1f, 1e-6f);
  EXPECT_NEAR(hi, 0.4f, 1e-6f);
}

// The corpus's valid models upload and draw, over a real placement, with no
// GL error; BoxTextured's logo shows (its pixels are not one flat colour per
// face), and the power-of-two path (boards without OES_texture_npot) draws
// it too.
TEST_F(GpuTest, CorpusModelsDrawOnTheTag) {
  const std::string corpus = "/usr/share/assimp/models/glTF2/";
  ModelStage stage;
  stage.pose = test::lookAt({0.12, -0.30, 0.22}, {0.0, 0.0, 0.03});
  ASSERT_NO_FATAL_FAILURE(initStage(stage, test::sharedCapabilities()));
  for (const char* name :
       {"BoxTextured-glTF/BoxTextured.gltf", "BoxTextured-glTF-Binary/BoxTextured.glb",
        "2CylinderEngine-glTF-Binary/2CylinderEngine.glb", "textureTransform/TextureTransformTest.gltf"}) {
    const std::string file = name;
    model::MeshModel model;
    std::string error;
    ASSERT_TRUE(model::loadGltfModel(corpus + file, {}, model, error)) << error;
    // Scaled to 8 cm across, whatever the file's size.
    const glm::vec3 extent = model.max_m - model.min_m;
    const double scale = 0.08 / std::max({extent.x, extent.y, extent.z});
    const glm::dmat4 world = model::worldFromModel(model, {{0.0, 0.0}, 0.4, scale});
    for (const bool power_of_two : {false, true}) {
      passes::ModelRendererSettings settings;
      settings.force_power_of_two = power_of_two;
      passes::ModelRenderer renderer;
      ASSERT_TRUE(renderer.init(test::sharedCapabilities(), stage.maps.storage(), model, world, settings, error))
          << file << ": " << error;
      ImageRGB8 result;
      ASSERT_TRUE(renderModel(stage, renderer, result, error)) << file << ": " << error;
      int covered = 0;
      std::vector<int> histogram(256, 0);
      for (std::size_t i = 0; i + 2 < result.pixels.size(); i += 3) {
        if (result.pixels[i] == 90 && result.pixels[i + 1] == 90 && result.pixels[i + 2] == 90) continue;
        ++covered;
        ++histogram[result.pixels[i + 1]];
      }
      int distinct = 0;
      for (int count : histogram) distinct += count > 0;
      std::printf("[ measure  ] %s%s: %zu triangles, %zu draws, %.1f KiB textures, %d px covered, %d green levels\n",
                  file.c_str(), power_of_two ? " (power-of-two path)" : "", renderer.stats().triangles,
                  renderer.stats().draw_pieces, renderer.stats().texture_bytes / 1024.0, covered, distinct);
      EXPECT_GT(covered, 2000) << file;
      if (file.find("BoxTextured") != std::string::npos) {
        EXPECT_GT(distinct, 40) << file << ": the logo must show";
      }
    }
  }
}

}  // namespace
}  // namespace probelight
