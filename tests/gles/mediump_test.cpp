// Numerical stability at 16-bit mediump: every fragment shader's CPU twin
// (shader_twins.hpp) run on the GPU tests' inputs at float and at
// glsl::Mediump16, the largest difference reported in the output's own
// units, and bounded. The float twin is also checked against the GPU
// (llvmpipe, highp), so the twins stay the shaders they claim to be.
//
// Each result line reads "[ mediump  ] shader | input | largest error at
// 16 bits | bound"; with PROBELIGHT_MEDIUMP_TABLE=FILE set, the rows are
// appended to FILE as a Markdown table (docs/mediump.md is made that way).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cosine_irradiance_reference.hpp"
#include "gles_test_support.hpp"
#include "ibl/glossy_maps.hpp"
#include "ibl/spherical_harmonics.hpp"
#include "ibl/surface_shading.hpp"
#include "glsl_precision.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/mirror_ball.hpp"
#include "core/ycbcr.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/cube_face_basis.hpp"
#include "passes/environment_maps.hpp"
#include "passes/ground_shadow.hpp"
#include "test_scenes.hpp"
#include "shader_twins.hpp"

namespace probelight {
namespace {

using glsl::Mediump16;
using test::GpuTest;

// Levels are 255 x a float code: a whole number of levels comes out within
// this of an integer.
constexpr double kLevelSlack = 1e-3;

// One row of the table: printed, and appended to $PROBELIGHT_MEDIUMP_TABLE.
void reportRow(const std::string& shader, const std::string& input, const std::string& error_at_16_bits,
               const std::string& bound) {
  std::printf("[ mediump  ] %s | %s | %s | %s\n", shader.c_str(), input.c_str(), error_at_16_bits.c_str(),
              bound.c_str());
  if (const char* path = std::getenv("PROBELIGHT_MEDIUMP_TABLE")) {
    if (FILE* file = std::fopen(path, "a")) {
      std::fprintf(file, "| `%s` | %s | %s | %s |\n", shader.c_str(), input.c_str(), error_at_16_bits.c_str(),
                   bound.c_str());
      std::fclose(file);
    }
  }
}

std::string format(const char* pattern, double a, double b = 0.0, double c = 0.0) {
  char text[256];
  std::snprintf(text, sizeof text, pattern, a, b, c);
  return text;
}

twin::Texture2D cameraTexture(const ImageRGB8& image) {
  twin::Texture2D texture;
  texture.width = image.width;
  texture.height = image.height;
  texture.linear = true;
  texture.texels.resize(static_cast<size_t>(image.width) * image.height);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const std::uint8_t* p = image.row(y) + 3 * x;
      texture.texels[static_cast<size_t>(y) * image.width + x] = glm::vec4(p[0], p[1], p[2], 255) / 255.0f;
    }
  return texture;
}

// The varying a cube-face pass interpolates at texel (x, y): the face's
// unnormalised direction, turned by `rotation` (probe_to_cube.vert).
glm::dvec3 faceVarying(int face, int x, int y, int n, const glm::dmat3& rotation) {
  const passes::FaceBasis& basis = passes::kFaceBases[static_cast<size_t>(face)];
  const double s = 2.0 * (x + 0.5) / n - 1.0, t = 2.0 * (y + 0.5) / n - 1.0;
  return rotation * (glm::dvec3(basis.center) + s * glm::dvec3(basis.s_axis) + t * glm::dvec3(basis.t_axis));
}

// Max - min of the bytes within the 4x4 pixels around `pixel`, per channel:
// what a sample moved by up to a pixel can read.
glm::dvec3 spreadAround(const ImageRGB8& image, const glm::dvec2& pixel) {
  const int x0 = static_cast<int>(std::floor(pixel.x)), y0 = static_cast<int>(std::floor(pixel.y));
  glm::dvec3 lo(255.0), hi(0.0);
  for (int y = y0 - 1; y <= y0 + 2; ++y)
    for (int x = x0 - 1; x <= x0 + 2; ++x) {
      const std::uint8_t* p = image.row(std::clamp(y, 0, image.height - 1)) + 3 * std::clamp(x, 0, image.width - 1);
      for (int c = 0; c < 3; ++c) {
        lo[c] = std::min(lo[c], double(p[c]));
        hi[c] = std::max(hi[c], double(p[c]));
      }
    }
  return hi - lo;
}

// The twins' 16-bit rounding is IEEE binary16's: where the compiler has
// _Float16 (GCC), roundToHalf agrees with its conversion on every value
// tried, normal, subnormal, overflowing and tied.
TEST(MediumpTwins, HalfRoundingIsIeeeBinary16) {
#if defined(__aarch64__)
  // AArch64 GCC's C++ front end before GCC 13 has no _Float16 (its C has);
  // __fp16 is the same IEEE binary16, converted by the FPU's FCVT.
  using Binary16 = __fp16;
#elif defined(__FLT16_MANT_DIG__)
  using Binary16 = _Float16;
#endif
#if defined(__aarch64__) || defined(__FLT16_MANT_DIG__)
  std::vector<double> values = {0.0, 1.0, 65504.0, 65519.99, 65520.0, 1e5, std::ldexp(1.0, -14), std::ldexp(1.0, -24),
                                std::ldexp(1.0, -25), std::ldexp(3.0, -26), 2049.0, 2051.0, 0.1, 1.0 / 3.0};
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  for (int i = 0; i < 200000; ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const double mantissa = 1.0 + static_cast<double>(state >> 11) / static_cast<double>(1ull << 53);
    const int exponent = static_cast<int>((state >> 3) % 48) - 30;
    values.push_back(((state & 1) ? -1.0 : 1.0) * std::ldexp(mantissa, exponent));
  }
  int differ = 0;
  for (const double v : values) {
    const double want = static_cast<double>(static_cast<Binary16>(static_cast<float>(v)));
    const double got = glsl::roundToHalf(static_cast<float>(v));
    differ += !(want == got || (std::isnan(want) && std::isnan(got)));
  }
  EXPECT_EQ(differ, 0) << "of " << values.size();
#else
  GTEST_SKIP() << "this compiler has no _Float16 to compare with";
#endif
}

// Stage 2 at both precisions on environment_maps_test.cpp's ball, 8-bit
// storage (a GPU without fragment highp seldom renders half floats).
// Compared in the camera's 8-bit levels, e = 255 linearToSrgb(linear *
// reflectance), as that test does.
TEST_F(GpuTest, ProbeToCubeTwinFollowsTheShaderAndStaysWithinMediumpsTexelReach) {
  const gles::Capabilities caps = test::sharedCapabilities().withoutExtensions();
  const ibl::MirrorBallView view = test::testBallView();
  const ImageRGB8 image = test::renderBallImage(view);
  std::string error;
  passes::CameraFrameTexture frame;
  ASSERT_TRUE(frame.init(caps, error)) << error;
  ASSERT_TRUE(frame.upload(image, error)) << error;
  passes::EnvironmentMaps maps;
  ASSERT_TRUE(maps.init(caps, {}, error)) << error;
  ASSERT_TRUE(maps.updateReflection(frame, view, test::kProbeReflectance, error)) << error;
  std::vector<float> gpu_validity;
  const auto gpu = maps.readReflection(error, &gpu_validity);
  ASSERT_TRUE(gpu) << error;

  const passes::ProbeToCubeUniforms u = passes::probeToCubeUniforms(view, test::kProbeReflectance);
  twin::ProbeToCubeInputs in{u.eye_ball,        u.eye_direction,       u.center_normalized, u.radius_over_depth,
                             u.distortion,      u.distortion_k3,       u.center_r2,         u.center_radial,
                             u.focal_over_size, u.center_texcoord,      u.center_texcoord_residual,
                             u.inverse_reflectance, u.storage_scale};
  in.normal_iterations = maps.settings().normal_iterations;
  in.srgb8 = true;
  const twin::Texture2D camera = cameraTexture(image);
  const int n = maps.settings().reflection_face_size;
  auto levels = [&](const glm::vec4& stored_texel) {
    // The 8-bit storage holds linearToSrgb(linear / scale); back to the camera's levels.
    glm::dvec3 out;
    for (int c = 0; c < 3; ++c)
      out[c] = 255.0 * ibl::linearToSrgb(ibl::srgbToLinear(stored_texel[c]) * u.storage_scale * test::kProbeReflectance);
    return out;
  };

  double largest_shift_px = 0.0;
  double faithful_excess = -1e9, faithful_max = 0.0, mediump_max = 0.0, mediump_excess = -1e9;
  std::vector<double> mediump_errors;
  int compared = 0, validity_mismatches = 0, mediump_validity_mismatches = 0;
  for (int face = 0; face < 6; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const glm::dvec3 varying = faceVarying(face, x, y, n, u.R_cam_from_world);
        glm::dvec2 texcoord_float, texcoord_16;
        const glm::vec4 at_float = twin::stored(
            twin::toDouble(twin::probeToCube<float>(in, twin::toS<float>(varying), camera, &texcoord_float)),
            twin::Storage::kRgba8);
        const glm::vec4 at_16 = twin::stored(
            twin::toDouble(twin::probeToCube<Mediump16>(in, twin::toS<Mediump16>(varying), camera, &texcoord_16)),
            twin::Storage::kRgba8);
        const glm::dvec2 shift_px = (texcoord_16 - texcoord_float) * glm::dvec2(image.width, image.height);
        const bool gpu_visible = gpu_validity[static_cast<size_t>(face * n * n + y * n + x)] > 0.5f;
        const bool float_visible = at_float.a > 0.5f, visible_16 = at_16.a > 0.5f;
        validity_mismatches += gpu_visible != float_visible;
        mediump_validity_mismatches += visible_16 != float_visible;
        if (!gpu_visible || !float_visible || !visible_16) continue;
        // Where the exact pixel lies (for the bilinear neighbourhood's spread),
        // and only texels whose 1-step Newton pixel has converged, as the GPU test.
        const glm::dvec3 direction = ibl::cubeTexelCenterDirection(face, x, y, n);
        const auto pixel = ibl::reflectedDirectionToPixel(view, direction, in.normal_iterations);
        const auto converged = ibl::reflectedDirectionToPixel(view, direction, 32);
        if (!pixel || !converged || glm::length(*converged - *pixel) > 0.05) continue;
        ++compared;
        largest_shift_px = std::max(largest_shift_px, glm::length(shift_px));

        const glm::dvec3 range = test::bilinearNeighbourhoodRange(image, *pixel);
        const glm::dvec3 wide_range = spreadAround(image, *pixel);
        const glm::dvec3 float_levels = levels(at_float), levels_16 = levels(at_16);
        glm::dvec3 gpu_levels;
        for (int c = 0; c < 3; ++c)
          gpu_levels[c] = 255.0 * ibl::linearToSrgb(gpu->texel(face, x, y)[c] * test::kProbeReflectance);
        for (int c = 0; c < 3; ++c) {
          // The GPU test's budget (environment_maps_test.cpp): llvmpipe's
          // 8-bit filter, 1 level plus range / 512, and 0.5 level of storage.
          const double faithful = std::abs(float_levels[c] - gpu_levels[c]);
          faithful_max = std::max(faithful_max, faithful);
          faithful_excess = std::max(faithful_excess, faithful - (1.5 + range[c] / 256.0));
          // At 16 bits the texture coordinate (in [0, 1]) keeps 11
          // significant bits: it moves by up to half an ulp, 2^-12 of the
          // image width past the middle (0.16 px at 640), and the geometry
          // before it by a few hundredths of a pixel more (its offsets from
          // the ball centre keep 11 bits of their own size); next to the
          // blind spot, where Newton's step amplifies rounding, by up to
          // 0.3 px. A sample moved by d < 1 px changes by at most d times
          // the spread of the 4x4 pixels around it. Bound: 1 level (the
          // storage's rounding on each side) plus 0.3 of that spread.
          const double at_16_bits = std::abs(levels_16[c] - float_levels[c]);
          mediump_errors.push_back(at_16_bits);
          mediump_max = std::max(mediump_max, at_16_bits);
          mediump_excess = std::max(mediump_excess, at_16_bits - (1.0 + 0.3 * wide_range[c]));
        }
      }
  std::sort(mediump_errors.begin(), mediump_errors.end());
  const double median = mediump_errors.empty() ? 0.0 : mediump_errors[mediump_errors.size() / 2];
  const double p99 = mediump_errors.empty() ? 0.0 : mediump_errors[mediump_errors.size() * 99 / 100];
  std::printf("[ measure  ] probe_to_cube twin: float vs GPU max %.3f levels (%d texels, %d validity mismatches); "
              "16 bits vs float: max %.2f, p99 %.2f, median %.2f levels, %d validity flips, shift %.2f px\n",
              faithful_max, compared, validity_mismatches, mediump_max, p99, median, mediump_validity_mismatches, largest_shift_px);
  reportRow("probe_to_cube.frag", "the GPU test's ball (640x480, 8-bit storage)",
            format("%.2f levels max, %.2f at the 99th percentile, %.2f median", mediump_max, p99, median),
            "1 level + 0.3 x the spread of the 4x4 pixels read");
  EXPECT_GT(compared, 3 * n * n);
  EXPECT_LE(faithful_excess, 0.0);
  EXPECT_LE(validity_mismatches, 4);
  EXPECT_LE(mediump_excess, 0.0);
  EXPECT_LE(mediump_validity_mismatches, 2 * n);
}

// A GPU cube map's texels as stored (8-bit storage: the sRGB code of
// linear / scale, and validity), from its decoded read-back.
twin::TextureCube storedCube(const ibl::CubeMapRGB& decoded, const std::vector<float>& validity, double scale) {
  twin::TextureCube cube;
  const int n = decoded.face_size;
  cube.face_size = n;
  for (int face = 0; face < 6; ++face) {
    cube.faces[static_cast<size_t>(face)].resize(static_cast<size_t>(n) * n);
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        glm::vec4 texel;
        for (int c = 0; c < 3; ++c)
          texel[c] = static_cast<float>(
              std::nearbyint(255.0 * ibl::linearToSrgb(decoded.texel(face, x, y)[c] / scale)) / 255.0);
        texel.a = static_cast<float>(std::nearbyint(255.0 * validity[static_cast<size_t>(face) * n * n + y * n + x]) / 255.0);
        cube.faces[static_cast<size_t>(face)][static_cast<size_t>(y) * n + x] = texel;
      }
  }
  return cube;
}

twin::FaceAxes faceAxes(int face) {
  const passes::FaceBasis& b = passes::kFaceBases[static_cast<size_t>(face)];
  return {glm::dvec3(b.center), glm::dvec3(b.s_axis), glm::dvec3(b.t_axis)};
}

// Largest |a - b| over a cube's rgb, in 8-bit levels.
double largestLevels(const twin::TextureCube& a, const twin::TextureCube& b) {
  double largest = 0.0;
  for (int face = 0; face < 6; ++face)
    for (size_t i = 0; i < a.faces[static_cast<size_t>(face)].size(); ++i)
      for (int c = 0; c < 3; ++c)
        largest = std::max(largest, 255.0 * std::abs(double(a.faces[static_cast<size_t>(face)][i][c]) -
                                                     double(b.faces[static_cast<size_t>(face)][i][c])));
  return largest;
}

double largestLevels(const twin::Texture2D& a, const twin::Texture2D& b) {
  double largest = 0.0;
  for (size_t i = 0; i < a.texels.size(); ++i)
    for (int c = 0; c < 3; ++c) largest = std::max(largest, 255.0 * std::abs(double(a.texels[i][c]) - double(b.texels[i][c])));
  return largest;
}

// The four passes of the diffuse map (cosine_irradiance.frag) at one precision.
template <class S> struct CosineChain {
  twin::TextureCube prefiltered, diffuse;
  twin::Texture2D east, north;
};

template <class S>
CosineChain<S> runCosineChain(const twin::TextureCube& reflection, double scale, const passes::EnvironmentMapSettings& settings) {
  twin::CosineDefines d;
  d.half_taps = settings.blur_half_taps;
  d.prefilter_factor = settings.reflection_face_size / settings.prefilter_face_size;
  d.latlong_rows = settings.intermediate_rows;
  d.srgb8 = true;
  const auto storage = twin::Storage::kRgba8;
  CosineChain<S> chain;
  chain.prefiltered = twin::renderCube<S>(settings.prefilter_face_size, storage, [&](int face, twin::vec2<S> st) {
    return twin::cosinePrefilter<S>(d, reflection, reflection.face_size, scale, scale, face, settings.prefilter_face_size, st);
  });
  chain.east = twin::renderLatLong<S>(d.latlong_rows, storage, [&](twin::vec2<S> st) {
    return twin::cosineEast<S>(d, chain.prefiltered, settings.prefilter_face_size, scale, scale, st);
  });
  chain.north = twin::renderLatLong<S>(d.latlong_rows, storage, [&](twin::vec2<S> st) {
    return twin::cosineNorth<S>(d, chain.east, scale, scale, st);
  });
  chain.diffuse = twin::renderCube<S>(settings.diffuse_face_size, storage, [&](int face, twin::vec2<S> st) {
    return twin::cosineResample<S>(d, chain.north, scale, scale, faceAxes(face), st);
  });
  return chain;
}

// The diffuse and glossy tests' input: the zenith-lamp room (lamp 10x the
// sky) as the reflection map of 8-bit maps, as a GPU without fragment
// highp (and so seldom with half-float targets) would store it.
bool initMapsWithRoom(passes::EnvironmentMaps& maps, ibl::CubeMapRGB& room, std::vector<float>& validity,
                      std::string& error) {
  if (!maps.init(test::sharedCapabilities().withoutExtensions(), {}, error)) return false;
  room = test::zenithLampRoom(maps.settings().reflection_face_size, 10.0, validity);
  return maps.setReflection(room, error, &validity);
}

// Stage 3 (the diffuse map by cosine passes) at both precisions on
// cosine_irradiance_test.cpp's zenith-lamp room (lamp 10x the sky, 8-bit
// storage). The float twin against the GPU; the 16-bit one against
// ibl::irradianceOverPiByCosinePasses within the bound that
// cosine_irradiance_reference.hpp derives, evaluated for 16 bits.
TEST_F(GpuTest, CosineIrradianceTwinFollowsTheShaderAndHoldsItsDerivedBoundAt16Bits) {
  passes::EnvironmentMaps maps;
  ibl::CubeMapRGB room;
  std::vector<float> validity;
  std::string error;
  ASSERT_TRUE(initMapsWithRoom(maps, room, validity, error)) << error;
  const passes::EnvironmentMapSettings& settings = maps.settings();
  ASSERT_TRUE(maps.updateDiffuse(error)) << error;
  std::vector<float> gpu_alpha, stored_validity;
  const auto gpu = maps.readDiffuse(error, &gpu_alpha);
  ASSERT_TRUE(gpu) << error;
  const auto reflection = maps.readReflection(error, &stored_validity);
  ASSERT_TRUE(reflection) << error;
  const double scale = maps.reflection().linear_scale;
  ASSERT_FLOAT_EQ(maps.diffuse().linear_scale, static_cast<float>(scale));
  const twin::TextureCube input = storedCube(*reflection, stored_validity, scale);

  const CosineChain<float> at_float = runCosineChain<float>(input, scale, settings);
  const CosineChain<Mediump16> at_16 = runCosineChain<Mediump16>(input, scale, settings);

  // The float twin is the GPU's pass: both store the same RGBA8 code, up to
  // one level where llvmpipe's own rounding (its pow, its sums' order) falls
  // on the other side of a code boundary; a level lost so in an intermediate
  // map moves the later weighted means (weights summing to 1) by at most one
  // more.
  const twin::TextureCube gpu_stored = storedCube(*gpu, gpu_alpha, scale);
  const double faithful = largestLevels(at_float.diffuse, gpu_stored);
  EXPECT_LE(faithful, 2.0);

  // At 16 bits: the reference's bound with u = 2^-11, and directions good
  // to 10 u: the azimuth 2 pi s of the east pass is rounded at up to 6.3,
  // half an ulp there is 4 u rad, and normalize, sin, cos and the tap
  // rotation add a few u more.
  const double u16 = std::ldexp(1.0, -11);
  const test::CosineReference ref = test::cosineIrradianceReference(room, validity, settings, passes::CubeStorage::kSrgb8,
                                                                    scale, 0.5, u16, 10.0 * u16);
  double excess = -1e30, largest_linear = 0.0, largest_relative_of_bound = 0.0;
  const int n = settings.diffuse_face_size;
  for (int face = 0; face < 6; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        for (int c = 0; c < 3; ++c) {
          const double got = ibl::srgbToLinear(at_16.diffuse.faces[static_cast<size_t>(face)][static_cast<size_t>(y) * n + x][c]) * scale;
          const double want = ref.rgb.texel(face, x, y)[c];
          const double bound =
              ref.tolerance.texel(face, x, y)[c] + test::storageRoundingBound(passes::CubeStorage::kSrgb8, want, scale, 0.6);
          largest_linear = std::max(largest_linear, std::abs(got - want));
          largest_relative_of_bound = std::max(largest_relative_of_bound, std::abs(got - want) / bound);
          excess = std::max(excess, std::abs(got - want) - bound);
        }
  const double pass_levels[4] = {largestLevels(at_16.prefiltered, at_float.prefiltered),
                                 largestLevels(at_16.east, at_float.east), largestLevels(at_16.north, at_float.north),
                                 largestLevels(at_16.diffuse, at_float.diffuse)};
  std::printf("[ measure  ] cosine passes twin: float vs GPU %.0f level(s); 16 bits vs float per pass (prefilter, "
              "east, north, resample): %.0f %.0f %.0f %.0f levels; 16 bits vs the reference: %.3g linear, %.2f of "
              "the bound\n",
              faithful, pass_levels[0], pass_levels[1], pass_levels[2], pass_levels[3], largest_linear,
              largest_relative_of_bound);
  const char* passes_names[4] = {"PREFILTER_PASS", "EAST_PASS", "NORTH_PASS", "RESAMPLE_PASS"};
  for (int p = 0; p < 4; ++p)
    reportRow(std::string("cosine_irradiance.frag ") + passes_names[p], "the GPU test's zenith-lamp room, 8-bit",
              format("%.0f level(s) of its 8-bit output", pass_levels[p]),
              p == 3 ? format("the chain: %.2f of the bound derived for 16 bits", largest_relative_of_bound)
                     : std::string("(the chain's bound, last row)"));
  EXPECT_LE(excess, 0.0);
}

// The glossy maps (glossy_lobe.frag, after cosine_irradiance.frag's
// prefilter) at both precisions on the same room. At 16 bits each map is
// compared with the float twin: the lobe weights are exp(-m s(a)) of a
// series with positive terms (glossy_lobe.frag says why), so they keep
// 16 bits' relative accuracy, and each output is a normalised weighted mean
// of stored values. Budget: the sums' rounding (2 x 17 terms and a
// division: 40 u, 2% of the value), plus a level of storage for each of
// the three maps made (a code that rounds the other way in the prefiltered
// or the intermediate map moves the later weighted means by at most that),
// plus directions good to 10 u rad (as the cosine passes'): the lobe's
// result then moves by up to 10 u rad, 10 u x n / 2 texels of an n-texel
// face, i.e. by that fraction of the largest step to a neighbouring texel
// of the float map there.
TEST_F(GpuTest, GlossyTwinFollowsTheShaderAndStaysWithinItsBudgetAt16Bits) {
  passes::EnvironmentMaps maps;
  ibl::CubeMapRGB room;
  std::vector<float> validity, stored_validity;
  std::string error;
  ASSERT_TRUE(initMapsWithRoom(maps, room, validity, error)) << error;
  const passes::EnvironmentMapSettings& settings = maps.settings();
  ASSERT_GT(settings.glossy_levels, 0);
  ASSERT_TRUE(maps.updateGlossy(error)) << error;
  const auto reflection = maps.readReflection(error, &stored_validity);
  ASSERT_TRUE(reflection) << error;
  const double scale = maps.reflection().linear_scale;
  const twin::TextureCube input = storedCube(*reflection, stored_validity, scale);

  for (int level = 0; level < settings.glossy_levels; ++level) {
    const ibl::GlossyLevelSettings lobe = passes::glossyLevelSettings(settings, level);
    twin::CosineDefines prefilter_defines;
    prefilter_defines.prefilter_factor = settings.reflection_face_size / lobe.prefilter_face_size;
    twin::GlossyUniforms u;
    u.half_taps = lobe.half_taps;
    u.tap_step_rad = static_cast<float>(ibl::glossyTapAngleRad(lobe.exponent, lobe.half_taps, 1));
    u.east_power = lobe.exponent + 1.0;
    u.north_power = lobe.exponent;
    u.input_scale = u.output_scale = u.prefiltered_scale = scale;
    u.prefiltered_face_size = lobe.prefilter_face_size;
    u.pole_cosine = static_cast<float>(std::cos(lobe.pole_direct_deg * M_PI / 180.0));
    auto run = [&](auto precision) {
      using S = decltype(precision);
      struct Maps {
        twin::TextureCube prefiltered, intermediate, map;
      } out;
      out.prefiltered = twin::renderCube<S>(lobe.prefilter_face_size, twin::Storage::kRgba8, [&](int face, twin::vec2<S> st) {
        return twin::cosinePrefilter<S>(prefilter_defines, input, input.face_size, scale, scale, face,
                                        lobe.prefilter_face_size, st);
      });
      twin::GlossyUniforms east = u;
      east.input_face_size = lobe.prefilter_face_size;
      out.intermediate = twin::renderCube<S>(lobe.intermediate_face_size, twin::Storage::kRgba8, [&](int face, twin::vec2<S> st) {
        return twin::glossyEast<S>(east, out.prefiltered, faceAxes(face), st);
      });
      twin::GlossyUniforms north = u;
      north.input_face_size = lobe.intermediate_face_size;
      out.map = twin::renderCube<S>(lobe.output_face_size, twin::Storage::kRgba8, [&](int face, twin::vec2<S> st) {
        return twin::glossyNorth<S>(north, out.intermediate, out.prefiltered, faceAxes(face), st);
      });
      return out;
    };
    const auto at_float = run(0.0f);
    const auto at_16 = run(Mediump16(0.0));
    std::vector<float> gpu_validity;
    const auto gpu = maps.readGlossy(level, error, &gpu_validity);
    ASSERT_TRUE(gpu) << error;
    // As the cosine chain: one level of the GPU's own rounding per stored map after the input.
    const double faithful = largestLevels(at_float.map, storedCube(*gpu, gpu_validity, scale));
    EXPECT_LE(faithful, 2.0) << "level " << level;

    double largest_levels = 0.0, excess = -1e30;
    const twin::TextureCube& a = at_16.map;
    const twin::TextureCube& b = at_float.map;
    const double shift_texels = 10.0 * std::ldexp(1.0, -11) * lobe.output_face_size / 2.0;
    // Per texel: the largest step to a neighbour on its face, in levels.
    auto neighbour_step = [&](int face, size_t i, int c) {
      const int nn = b.face_size, x = static_cast<int>(i) % nn, y = static_cast<int>(i) / nn;
      const auto& f = b.faces[static_cast<size_t>(face)];
      double step = 0.0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = std::clamp(x + dx, 0, nn - 1), yy = std::clamp(y + dy, 0, nn - 1);
          step = std::max(step, 255.0 * std::abs(double(f[static_cast<size_t>(yy) * nn + xx][c]) - double(f[i][c])));
        }
      return step;
    };
    double largest_bound = 0.0;
    int unseen = 0;
    for (int face = 0; face < 6; ++face)
      for (size_t i = 0; i < a.faces[static_cast<size_t>(face)].size(); ++i)
        for (int c = 0; c < 3; ++c) {
          // Where the lobe saw nothing (coverage stored as 0, deep in the
          // blind spot) the texel holds no light: the float twin divides a
          // sum of ~1e-7 by another, 16 bits underflow to 0 (black, as the
          // mirror map is there), and neither is data; counted apart.
          if (b.faces[static_cast<size_t>(face)][i].a == 0.0f) {
            unseen += c == 0;
            continue;
          }
          const double levels_16 = 255.0 * a.faces[static_cast<size_t>(face)][i][c];
          const double levels_float = 255.0 * b.faces[static_cast<size_t>(face)][i][c];
          const double difference = std::abs(levels_16 - levels_float);
          largest_levels = std::max(largest_levels, difference);
          // 2% of the linear value is at most 2% / 2.4 ... 2% of its sRGB code; 2% of the code bounds both.
          const double bound = 0.02 * levels_float + 3.0 + shift_texels * neighbour_step(face, i, c);
          largest_bound = std::max(largest_bound, bound);
          excess = std::max(excess, difference - bound);
        }
    const double levels_prefilter = largestLevels(at_16.prefiltered, at_float.prefiltered);
    const double levels_east = largestLevels(at_16.intermediate, at_float.intermediate);
    std::printf("[ measure  ] glossy level %d (n = %g) twin: float vs GPU %.0f level(s); 16 bits vs float: prefilter "
                "%.0f, east %.0f, north %.0f levels (bound up to %.1f; %d texels saw nothing)\n",
                level, lobe.exponent, faithful, levels_prefilter, levels_east, largest_levels, largest_bound, unseen);
    const std::string input_name = "the zenith-lamp room, glossy level " + std::to_string(level) + " (n = " +
                                   std::to_string(static_cast<int>(lobe.exponent)) + "), 8-bit";
    reportRow("glossy_lobe.frag EAST_PASS", input_name, format("%.0f level(s)", levels_east), "(the map's, next row)");
    reportRow("glossy_lobe.frag NORTH_PASS", input_name,
              format("%.0f level(s); %.0f texels that saw nothing (coverage 0) left out", largest_levels, unseen),
              format("2%% + 3 levels + %.2f x the step to a neighbour (at most %.1f levels here)", shift_texels,
                     largest_bound));
    EXPECT_LE(excess, 0.0) << "level " << level;
  }
}

ibl::CubeMapRGB decodedCube(const twin::TextureCube& stored_cube, double scale) {
  ibl::CubeMapRGB cube(stored_cube.face_size);
  for (int face = 0; face < 6; ++face)
    for (size_t i = 0; i < stored_cube.faces[static_cast<size_t>(face)].size(); ++i)
      for (int c = 0; c < 3; ++c)
        cube.faces[static_cast<size_t>(face)][i][c] =
            static_cast<float>(ibl::srgbToLinear(stored_cube.faces[static_cast<size_t>(face)][i][c]) * scale);
  return cube;
}

// The diffuse map from SH9 (sh9_irradiance.frag) at both precisions, with
// the coefficients sh9_and_blend_test.cpp's way makes them (projectToSH9
// of the read-back reflection map), here of the zenith-lamp room. Bound at
// 16 bits: 14 u x the sum of |p_k| (the shader's comment and
// tests/ibl/spherical_harmonics_test.cpp derive it) plus a level of storage.
TEST_F(GpuTest, Sh9TwinFollowsTheShaderAndHoldsItsBoundAt16Bits) {
  passes::EnvironmentMaps maps;
  ibl::CubeMapRGB room;
  std::vector<float> validity, read_validity;
  std::string error;
  ASSERT_TRUE(initMapsWithRoom(maps, room, validity, error)) << error;
  const auto reflection = maps.readReflection(error, &read_validity);
  ASSERT_TRUE(reflection) << error;
  const ibl::SH9RGB sh = ibl::projectToSH9(*reflection, &read_validity);
  ASSERT_TRUE(maps.updateDiffuseFromSH9(sh, error)) << error;
  std::vector<float> gpu_alpha;
  const auto gpu = maps.readDiffuse(error, &gpu_alpha);
  ASSERT_TRUE(gpu) << error;
  const double scale = maps.diffuse().linear_scale;
  const std::array<glm::dvec3, 9> polynomial = ibl::sh9DiffusePolynomial(sh);
  std::array<glm::dvec3, 9> as_floats;  // the uniforms GL gets
  glm::dvec3 sum_abs(0.0);
  for (int k = 0; k < 9; ++k) {
    as_floats[static_cast<size_t>(k)] = glm::dvec3(glm::vec3(polynomial[static_cast<size_t>(k)]));
    sum_abs += glm::abs(polynomial[static_cast<size_t>(k)]);
  }
  const int n = maps.settings().diffuse_face_size;
  auto run = [&](auto precision) {
    using S = decltype(precision);
    return twin::renderCube<S>(n, twin::Storage::kRgba8, [&](int face, twin::vec2<S> st) {
      return twin::sh9Irradiance<S>(as_floats, scale, true, faceAxes(face), st);
    });
  };
  const twin::TextureCube at_float = run(0.0f), at_16 = run(Mediump16(0.0));
  EXPECT_LE(largestLevels(at_float, storedCube(*gpu, gpu_alpha, scale)), 1.0);
  const double u16 = std::ldexp(1.0, -11);
  double largest_levels = 0.0, excess = -1e30, largest_bound = 0.0;
  for (int face = 0; face < 6; ++face)
    for (size_t i = 0; i < at_16.faces[static_cast<size_t>(face)].size(); ++i)
      for (int c = 0; c < 3; ++c) {
        const double code_float = at_float.faces[static_cast<size_t>(face)][i][c];
        const double code_16 = at_16.faces[static_cast<size_t>(face)][i][c];
        // The linear bound in codes: through the sRGB curve's slope at the
        // value (its decode slope is smallest at the top, so this is safe).
        const double linear_bound = 14.0 * u16 * sum_abs[c];
        const double bound_levels = 1.0 + 255.0 * linear_bound / (scale * test::srgbDecodeSlope(std::max(code_float, code_16)));
        largest_levels = std::max(largest_levels, 255.0 * std::abs(code_16 - code_float));
        largest_bound = std::max(largest_bound, bound_levels);
        excess = std::max(excess, 255.0 * std::abs(code_16 - code_float) - bound_levels);
      }
  std::printf("[ measure  ] sh9 twin: 16 bits vs float %.0f level(s), bound up to %.1f\n", largest_levels, largest_bound);
  reportRow("sh9_irradiance.frag", "SH9 of the zenith-lamp room, 8-bit", format("%.0f level(s)", largest_levels),
            format("1 level + 14 u x the sum of abs(p_k) (up to %.1f levels here)", largest_bound));
  EXPECT_LE(excess, 0.0);
}

// The object's shading (sphere_object.frag, the mirror rung) at both
// precisions over the visible half of a sphere and over a close-up of its
// highlight, with the twin's maps of the zenith-lamp room, for the default
// material and for the sharpest highlight probelight.yaml accepts
// (shininess 4096). The float twin is checked against ibl::shadeSurface,
// the shader's CPU reference. Bound at 16 bits: the normal, normalised in
// 16 bits, points within 4 u rad of the float one (the mirror direction
// within 8 u, but it also turns twice as fast across the image), so every
// term of the output moves by at most what 4 u rad of normal moves it:
// 4 u / (the normal's angle per pixel) times the largest step to a
// neighbouring pixel; plus the sums' rounding (8 u, 1% covers it) and a
// level of output rounding.
TEST(MediumpTwins, SphereShadingKeepsItsHighlightAt16Bits) {
  std::vector<float> validity;
  const ibl::CubeMapRGB room = test::zenithLampRoom(64, 10.0, validity);
  double scale = 1.0;
  for (const auto& face : room.faces)
    for (const glm::vec3& t : face) scale = std::max({scale, double(t.r), double(t.g), double(t.b)});
  twin::TextureCube reflection;
  reflection.face_size = room.face_size;
  for (int face = 0; face < 6; ++face)
    for (size_t i = 0; i < room.faces[static_cast<size_t>(face)].size(); ++i) {
      glm::dvec4 linear(glm::dvec3(room.faces[static_cast<size_t>(face)][i]) / scale, validity[face * room.face_size * room.face_size + i]);
      for (int c = 0; c < 3; ++c) linear[c] = ibl::linearToSrgb(linear[c]);
      reflection.faces[static_cast<size_t>(face)].push_back(twin::stored(linear, twin::Storage::kRgba8));
    }
  passes::EnvironmentMapSettings settings;
  const twin::TextureCube diffuse = runCosineChain<float>(reflection, scale, settings).diffuse;
  const ibl::CubeMapRGB diffuse_decoded = decodedCube(diffuse, scale), reflection_decoded = decodedCube(reflection, scale);

  // A 64 x 64 image of a unit sphere from 12 radii away.
  const glm::dvec3 eye = 12.0 * glm::normalize(glm::dvec3(0.3, -0.8, 0.5));
  const glm::dvec3 forward = -glm::normalize(eye), right = glm::normalize(glm::cross(forward, glm::dvec3(0, 0, 1))),
                   up = glm::cross(right, forward);
  struct Material {
    const char* name;
    double k_specular, shininess;
  };
  for (const Material material : {Material{"default material (k_s 0.25, shininess 48)", 0.25, 48.0},
                                  Material{"shininess 4096 (the largest accepted)", 0.25, 4096.0}})
  for (const bool close_up : {false, true}) {
    twin::SphereUniforms u;
    u.k_specular = material.k_specular;
    u.shininess = material.shininess;
    u.k_reflect = 0.08;
    u.highlight_direction_w = glm::normalize(glm::dvec3(0.1, 0.05, 1.0));  // the room's zenith lamp
    u.highlight_rgb = glm::dvec3(3.0, 2.7, 2.4);
    u.diffuse_face_size = diffuse.face_size;
    u.diffuse_scale = scale;
    u.reflection_face_size = reflection.face_size;
    u.reflection_scale = scale;
    ibl::SurfaceMaterial reference_material;
    reference_material.k_specular = static_cast<float>(u.k_specular);
    reference_material.shininess = static_cast<float>(u.shininess);
    reference_material.k_reflect = static_cast<float>(u.k_reflect);
    ibl::SceneLighting lighting;
    lighting.highlight_direction_w = glm::vec3(u.highlight_direction_w);
    lighting.highlight_rgb = glm::vec3(u.highlight_rgb);
    // Where the highlight peaks, seen from the sphere's centre (the eye is
    // 12 radii away, so every point sees it at nearly the same half vector).
    const glm::dvec3 half_vector = glm::normalize(u.highlight_direction_w + glm::normalize(eye));

    constexpr int kSize = 96;
    std::vector<glm::dvec3> code_float(kSize * kSize, glm::dvec3(-1.0)), code_16(kSize * kSize, glm::dvec3(-1.0));
    double faithful = 0.0;
    for (int py = 0; py < kSize; ++py)
      for (int px = 0; px < kSize; ++px) {
        // Orthographic enough at 12 radii: the pixel's point on the sphere;
        // in the close-up, normals within 4 lobe widths of the half vector.
        const double sx = 2.0 * (px + 0.5) / kSize - 1.0, sy = 1.0 - 2.0 * (py + 0.5) / kSize;
        const double r2 = sx * sx + sy * sy;
        if (!close_up && r2 >= 0.98) continue;
        const double lobe_rad = std::sqrt(2.0 / u.shininess);
        const glm::dvec3 normal =
            close_up ? glm::normalize(half_vector + 4.0 * lobe_rad * (sx * right + sy * glm::normalize(glm::cross(half_vector, right))))
                     : sx * right + sy * up - std::sqrt(1.0 - r2) * forward;
        const glm::dvec3 to_eye = eye - normal;  // the varying, unnormalised
        const glm::vec4 f = twin::stored(
            twin::toDouble(twin::sphereObject<float>(u, diffuse, reflection, twin::toS<float>(normal), twin::toS<float>(to_eye))),
            twin::Storage::kRgba8);
        const glm::vec4 h = twin::stored(twin::toDouble(twin::sphereObject<Mediump16>(u, diffuse, reflection,
                                                                                       twin::toS<Mediump16>(normal),
                                                                                       twin::toS<Mediump16>(to_eye))),
                                         twin::Storage::kRgba8);
        const glm::vec3 reference = ibl::shadeSurface(glm::vec3(normal), glm::vec3(glm::normalize(to_eye)), diffuse_decoded,
                                                      reflection_decoded, reference_material, lighting);
        for (int c = 0; c < 3; ++c) {
          code_float[static_cast<size_t>(py * kSize + px)][c] = 255.0 * f[c];
          code_16[static_cast<size_t>(py * kSize + px)][c] = 255.0 * h[c];
          faithful = std::max(faithful, std::abs(255.0 * f[c] - 255.0 * ibl::linearToSrgb(std::clamp(double(reference[c]), 0.0, 1.0))));
        }
      }
    const double lobe_rad = std::sqrt(2.0 / u.shininess);
    const double angle_per_pixel_rad = close_up ? 8.0 * lobe_rad / kSize : 2.0 / kSize;
    const double shift_px = 4.0 * std::ldexp(1.0, -11) / angle_per_pixel_rad;
    double largest_levels = 0.0, excess = -1e30;
    for (int py = 1; py + 1 < kSize; ++py)
      for (int px = 1; px + 1 < kSize; ++px) {
        const glm::dvec3 a = code_float[static_cast<size_t>(py * kSize + px)];
        if (a.x < 0.0) continue;
        double step = 0.0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const glm::dvec3 b = code_float[static_cast<size_t>((py + dy) * kSize + px + dx)];
            if (b.x >= 0.0) step = std::max(step, glm::length(b - a));
          }
        for (int c = 0; c < 3; ++c) {
          const double difference = std::abs(code_16[static_cast<size_t>(py * kSize + px)][c] - a[c]);
          largest_levels = std::max(largest_levels, difference);
          excess = std::max(excess, difference - (1.0 + 0.01 * a[c] + shift_px * step));
        }
      }
    const std::string view = close_up ? "the highlight close up (8 lobe widths across)" : "the whole sphere";
    std::printf("[ measure  ] sphere_object twin, %s, %s: float vs ibl::shadeSurface %.2f levels; 16 bits vs float %.0f "
                "levels (excess over the bound %.1f)\n",
                material.name, view.c_str(), faithful, largest_levels, excess);
    reportRow("sphere_object.frag", std::string("zenith-lamp room, ") + material.name + ", " + view,
              format("%.0f level(s) of the 8-bit output", largest_levels),
              format("1 level + 1%% + %.2f x the step to a neighbouring pixel", shift_px));
    EXPECT_LE(faithful, 1.0) << material.name;
    EXPECT_LE(excess, 0.0) << material.name;
  }
}

// Depth packed into RGBA8 (depth_packing.glsl, for GPUs without depth
// textures: shadow_depth.frag packs, ground_shadow.frag unpacks), round trip
// at both precisions over [0, 1] in steps of 1/65536 and at 1 itself.
// Float: within one step of 16 bits (half a step of rounding, or the
// saturation of the bytes next to 1). 16 bits: the packed value
// depth * 65535 / 256 < 256 is rounded to 11 significant bits (2^-11 of
// depth) and the unpacked sum once more (half of that): 1.5 x 2^-11.
TEST(MediumpTwins, PackedDepthSurvivesTheRoundTripAt16Bits) {
  double largest_float = 0.0, largest_16 = 0.0;
  bool all_finite = true;
  for (int i = 0; i <= 65536; ++i) {
    const double depth = i / 65536.0;
    auto round_trip = [&](auto precision) {
      using S = decltype(precision);
      const glm::vec4 stored_texel = twin::stored(twin::toDouble(twin::packDepth<S>(S(depth))), twin::Storage::kRgba8);
      return double(twin::unpackDepth<S>(twin::toS<S>(glm::dvec4(stored_texel))));
    };
    const double at_float = round_trip(0.0f), at_16 = round_trip(Mediump16(0.0));
    all_finite = all_finite && std::isfinite(at_float) && std::isfinite(at_16);
    largest_float = std::max(largest_float, std::abs(at_float - depth));
    largest_16 = std::max(largest_16, std::abs(at_16 - depth));
  }
  std::printf("[ measure  ] packed depth round trip: float %.2e, 16 bits %.2e (2^-11 = %.2e)\n", largest_float,
              largest_16, std::ldexp(1.0, -11));
  reportRow("depth_packing.glsl (shadow_depth.frag, ground_shadow.frag)", "depth 0 to 1 in 65,536 steps, and 1",
            format("%.1e of the depth range", largest_16), "1.5 x 2^-11 = 7.3e-4");
  EXPECT_TRUE(all_finite);
  EXPECT_LE(largest_float, 1.0 / 65535.0 + 1e-9);
  EXPECT_LE(largest_16, 1.5 * std::ldexp(1.0, -11));
}

// The ratio composite of the shadowed ground (ground_composite.frag) at both
// precisions over a whole frame: the GPU test's ball frame at 640 x 480, and
// the same scene at 1920 x 1080, under a fraction texture with a penumbra.
// The camera texcoord is gl_FragCoord / size: at 16 bits the window
// position x + 0.5 is exact below 1024 and rounds to an integer above (a
// half-pixel move), and the quotient keeps 11 bits (half an ulp: 2^-12 of
// the width past the middle). Bound: a level of each side's rounding plus
// that move (0.5 px past 1024, else 2^-12 x the width) times the largest
// step to a neighbouring camera pixel.
TEST(MediumpTwins, GroundCompositeAt16BitsMovesTheCameraSampleByUnderAPixel) {
  for (const bool full_hd : {false, true}) {
    ibl::MirrorBallView view = test::testBallView();
    if (full_hd) {
      view.camera.width_px = 1920;
      view.camera.height_px = 1080;
      view.camera.fx_px *= 3.0;
      view.camera.fy_px *= 3.0;
      view.camera.cx_px = 959.5;
      view.camera.cy_px = 539.5;
    }
    const ImageRGB8 image = test::renderBallImage(view);
    const twin::Texture2D camera = cameraTexture(image);
    twin::Texture2D fraction;
    fraction.width = fraction.height = 256;
    fraction.linear = true;
    for (int y = 0; y < 256; ++y)
      for (int x = 0; x < 256; ++x) {
        // A round shadow (40% light) with a soft edge, stored in bytes.
        const double r = std::hypot(x - 128.0, y - 128.0);
        const double f = 0.4 + 0.6 * std::clamp((r - 60.0) / 30.0, 0.0, 1.0);
        fraction.texels.push_back(glm::vec4(static_cast<float>(std::nearbyint(f * 255.0) / 255.0)));
      }
    const int w = image.width, h = image.height;
    double largest = 0.0, excess = -1e30;
    const double move_px = w > 1024 ? 0.5 + std::ldexp(1.0, -12) * w : std::ldexp(1.0, -12) * w;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const glm::dvec2 frag_coord(x + 0.5, (h - 1 - y) + 0.5);  // GL's window rows run bottom up
        const glm::dvec2 region_uv((x + 0.5) / w, (y + 0.5) / h);
        const glm::vec4 f = twin::stored(twin::toDouble(twin::groundComposite<float>(camera, fraction, {w, h},
                                                                                  twin::toS<float>(frag_coord),
                                                                                  twin::toS<float>(region_uv))),
                                         twin::Storage::kRgba8);
        const glm::vec4 m = twin::stored(twin::toDouble(twin::groundComposite<Mediump16>(
                                             camera, fraction, {w, h}, twin::toS<Mediump16>(frag_coord),
                                             twin::toS<Mediump16>(region_uv))),
                                         twin::Storage::kRgba8);
        double step = 0.0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const std::uint8_t* a = image.row(std::clamp(y + dy, 0, h - 1)) + 3 * std::clamp(x + dx, 0, w - 1);
            const std::uint8_t* b = image.row(y) + 3 * x;
            for (int c = 0; c < 3; ++c) step = std::max(step, std::abs(double(a[c]) - double(b[c])));
          }
        for (int c = 0; c < 3; ++c) {
          const double difference = 255.0 * std::abs(double(m[c]) - double(f[c]));
          largest = std::max(largest, difference);
          excess = std::max(excess, difference - (1.0 + move_px * step) - kLevelSlack);
        }
      }
    const std::string input = full_hd ? "the ball scene at 1920x1080, a soft shadow" : "the GPU test's ball frame (640x480), a soft shadow";
    std::printf("[ measure  ] ground_composite twin, %dx%d: 16 bits vs float %.0f levels (bound: 1 + %.2f px x step)\n", w, h,
                largest, move_px);
    reportRow("ground_composite.frag", input, format("%.0f level(s)", largest),
              format("1 level + %.2f px x the step to a neighbouring camera pixel", move_px));
    EXPECT_LE(excess, 0.0) << w << "x" << h;
  }
}

// Y'CbCr planes to R'G'B' (camera_yuv_planes.frag) for every standard and
// range, over a lattice of codes. Float: the decoder's own matrix in double
// within a tenth of a level. 16 bits: three products and two sums of O(1)
// values and the offset, each rounded to 2^-12 at most: under 1.5 x 10^-3,
// 0.4 level before the output rounds; bound 1 level.
TEST(MediumpTwins, YuvPlanesConvertWithinALevelAt16Bits) {
  double largest_16 = 0.0, largest_float = 0.0;
  for (const YcbcrMatrix matrix : {YcbcrMatrix::kRec601, YcbcrMatrix::kRec709, YcbcrMatrix::kRec2020})
    for (const bool full_range : {true, false}) {
      const YcbcrDecoding decoding = ycbcrDecoding({matrix, full_range});
      for (int yc = 0; yc < 256; yc += 3)
        for (int cb = 0; cb < 256; cb += 3)
          for (int cr = 0; cr < 256; cr += 3) {
            const glm::dvec3 code(yc / 255.0, cb / 255.0, cr / 255.0);
            const glm::vec4 f = twin::stored(twin::toDouble(twin::yuvPlanes<float>(decoding.matrix, decoding.offset, twin::toS<float>(code))),
                                             twin::Storage::kRgba8);
            const glm::vec4 m = twin::stored(
                twin::toDouble(twin::yuvPlanes<Mediump16>(decoding.matrix, decoding.offset, twin::toS<Mediump16>(code))),
                twin::Storage::kRgba8);
            for (int c = 0; c < 3; ++c) {
              double exact = decoding.offset[c];
              for (int k = 0; k < 3; ++k) exact += double(decoding.matrix[3 * k + c]) * code[k];
              largest_float = std::max(largest_float, std::abs(255.0 * f[c] - std::nearbyint(255.0 * std::clamp(exact, 0.0, 1.0))));
              largest_16 = std::max(largest_16, 255.0 * std::abs(double(m[c]) - double(f[c])));
            }
          }
    }
  std::printf("[ measure  ] camera_yuv_planes twin: float vs double %.0f, 16 bits vs float %.0f level(s)\n", largest_float,
              largest_16);
  reportRow("camera_yuv_planes.frag", "every standard and range, codes in steps of 3", format("%.0f level(s)", largest_16),
            "1 level");
  EXPECT_LE(largest_float, 1.0 + kLevelSlack);
  EXPECT_LE(largest_16, 1.0 + kLevelSlack);
}

// One light's ground shadow (ground_shadow.frag, over a packed RGBA8 depth
// map that shadow_depth.frag packed at the same precision) for a 7 cm
// sphere resting on the ground, at both precisions. The map is the
// sphere's far side as seen from the light, exactly (the GPU rasterises a
// tessellated sphere), so only precision differs. The output is the
// light's hidden share; at 16 bits a tap flips where the stored and the
// ground depths are within the rounding of either (2.4e-4 packed, 2^-12
// the varying), i.e. along the contact's edge and the shadow's outline,
// where the float result is itself between 0 and the share. Bound: a tap
// (1/16 of the share) per texel everywhere, plus the output's own rounding
// (the share, the count's quotient and their product: 4 x 2^-11 of the
// share, 64 x 2^-11 taps), and the shadow's total (its sum over the
// texels) within 1% of the float one.
TEST(MediumpTwins, GroundShadowAt16BitsFlipsAtMostATapAtItsEdges) {
  const double radius_m = 0.035;
  const glm::dvec3 centre(0.0, 0.0, radius_m);
  const glm::dvec3 light = glm::normalize(glm::dvec3(0.5, 0.2, 0.8));
  const passes::LightView view = passes::lightViewFor(light, centre, radius_m);
  const int map_size = passes::GroundShadowSettings{}.shadow_map_size_px;
  const int ground_size = passes::GroundShadowSettings{}.ground_texture_size_px;
  twin::GroundShadowUniforms u;
  u.share = glm::dvec3(0.35, 0.3, 0.25);
  u.tan_cone = std::tan(0.12);
  u.ground_gradient = view.ground_depth_gradient_per_uv;
  u.map_width_m = view.width_m;
  u.depth_range_m = view.depth_m;
  u.texel_uv = 1.0 / map_size;
  u.bias01 = passes::kShadowBias01;
  for (const glm::vec2& tap : passes::shadowDiscTaps()) u.taps.push_back(glm::dvec2(tap));
  // clip.xy is the offset across the light from the sphere's centre, in
  // units of the frustum's half width.
  const double half = view.width_m / 2.0;
  auto shadow_map = [&](auto precision) {
    using S = decltype(precision);
    twin::Texture2D map;
    map.width = map.height = map_size;
    for (int y = 0; y < map_size; ++y)
      for (int x = 0; x < map_size; ++x) {
        const double cx = 2.0 * (x + 0.5) / map_size - 1.0, cy = 2.0 * (y + 0.5) / map_size - 1.0;
        const double rho2 = (cx * cx + cy * cy) * half * half;
        glm::vec4 texel(0.0f);  // cleared: depth 0, empty
        if (rho2 < radius_m * radius_m) {
          // The far side: depth01 = (half - light . (p - c)) / (2 half), light . (p - c) = -sqrt(R^2 - rho^2).
          const double depth01 = (half + std::sqrt(radius_m * radius_m - rho2)) / (2.0 * half);
          texel = twin::stored(twin::toDouble(twin::packDepth<S>(S(depth01))), twin::Storage::kRgba8);
        }
        map.texels.push_back(texel);
      }
    return map;
  };
  const twin::Texture2D map_float = shadow_map(0.0f), map_16 = shadow_map(Mediump16(0.0));
  const ibl::GroundRegion region{{centre.x, centre.y}, 0.25};
  double largest_taps = 0.0, total_float = 0.0, total_16 = 0.0;
  int shadowed = 0;
  for (int j = 0; j < ground_size; ++j)
    for (int i = 0; i < ground_size; ++i) {
      const glm::dvec2 ground = region.centre_w + region.half_size_m * glm::dvec2(2.0 * (i + 0.5) / ground_size - 1.0,
                                                                                  2.0 * (j + 0.5) / ground_size - 1.0);
      const glm::dvec3 clip = glm::dvec3(view.clip_from_world * glm::dvec4(ground, 0.0, 1.0));
      const glm::dvec4 f = twin::toDouble(twin::groundShadow<float>(u, map_float, twin::toS<float>(clip)));
      const glm::dvec4 m = twin::toDouble(twin::groundShadow<Mediump16>(u, map_16, twin::toS<Mediump16>(clip)));
      largest_taps = std::max(largest_taps, std::abs(m.x - f.x) / u.share.x * passes::kShadowTaps);
      total_float += f.x;
      total_16 += m.x;
      shadowed += f.x > 0.0;
    }
  const double total_relative = std::abs(total_16 - total_float) / total_float;
  std::printf("[ measure  ] ground_shadow twin: %d texels in shadow; 16 bits vs float: largest %.2f taps, total %.3f%%\n",
              shadowed, largest_taps, 100.0 * total_relative);
  reportRow("ground_shadow.frag", "a 7 cm sphere on the ground, light at 53 deg elevation, packed depth",
            format("%.0f tap(s) of 16 at a texel; the shadow's total %.2f%% off", largest_taps, 100.0 * total_relative),
            "1 tap a texel (+ the output's rounding); the total within 1%");
  EXPECT_GT(shadowed, 1000);
  EXPECT_LE(largest_taps, 1.0 + 4.0 * passes::kShadowTaps * std::ldexp(1.0, -11));
  EXPECT_LE(total_relative, 0.01);
}

// The shaders that only pass a texel on (image_quad.frag, the camera
// background; camera_external.frag, the imported camera buffer): a byte
// k / 255 held at 16 bits is within 2^-12 of itself, so it stores back as k.
// And color_transfer.glsl's round trip, which every 8-bit map read and
// write makes: each code decoded and encoded again at 16 bits, against the
// float twin: within a level (the decode's 11 bits are 2^-11 relative, the
// encode's pow another few, and a level is 0.4% to 10% of the value).
TEST(MediumpTwins, PassThroughShadersKeepEveryByteAndTheSrgbRoundTripItsLevel) {
  int pass_through_changed = 0;
  double round_trip_16 = 0.0, round_trip_float = 0.0;
  for (int k = 0; k < 256; ++k) {
    const double code = k / 255.0;
    const glm::vec4 passed =
        twin::stored(twin::toDouble(glsl::vec4<Mediump16>(Mediump16(code), Mediump16(code), Mediump16(code), Mediump16(1.0))),
                     twin::Storage::kRgba8);
    pass_through_changed += std::nearbyint(255.0 * passed.x) != k;
    auto round_trip = [&](auto precision) {
      using S = decltype(precision);
      const twin::vec3<S> linear = twin::srgbToLinear(twin::vec3<S>(S(code)));
      return 255.0 * double(twin::linearToSrgb(linear).x);
    };
    round_trip_16 = std::max(round_trip_16, std::abs(round_trip(Mediump16(0.0)) - k));
    round_trip_float = std::max(round_trip_float, std::abs(round_trip(0.0f) - k));
  }
  std::printf("[ measure  ] pass-through: %d bytes changed; sRGB decode + encode: float %.3f, 16 bits %.3f levels\n",
              pass_through_changed, round_trip_float, round_trip_16);
  reportRow("image_quad.frag, camera_external.frag", "every byte", format("%.0f bytes changed", pass_through_changed),
            "0");
  reportRow("color_transfer.glsl", "every code decoded and encoded again", format("%.2f levels before the output rounds", round_trip_16),
            "1 level");
  EXPECT_EQ(pass_through_changed, 0);
  EXPECT_LT(round_trip_float, 0.05);
  EXPECT_LE(round_trip_16, 1.0);
}

}  // namespace
}  // namespace probelight
