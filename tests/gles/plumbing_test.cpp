// EGL context, capability probe, shader error reporting and the render
// target's screen convention, on the real Mesa driver.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "gles/embedded_shaders.hpp"
#include "gles/gl_objects.hpp"
#include "gles/render_target.hpp"
#include "gles_test_support.hpp"
#include "passes/environment_maps.hpp"

namespace probelight {
namespace {

using test::GpuTest;

TEST_F(GpuTest, HeadlessContextIsCurrentAndNamesItsPlatform) {
  EXPECT_EQ(eglGetCurrentContext(), context_->context());
  const std::string platform = context_->platformName();
  EXPECT_TRUE(platform == "surfaceless" || platform == "device" || platform == "default+pbuffer") << platform;
  // A surfaceless context has no surface; the pbuffer fallback must have one.
  EXPECT_EQ(context_->surfaceKind() == gles::EglSurfaceKind::kNone, context_->surface() == EGL_NO_SURFACE);
}

TEST_F(GpuTest, CapabilitiesAreCoherent) {
  const gles::Capabilities& caps = test::sharedCapabilities();
  EXPECT_FALSE(caps.renderer.empty());
  EXPECT_NE(caps.version.find("OpenGL ES"), std::string::npos) << caps.version;
  // GLES 2.0 minimums (section 6.2, table 6.20): 64 px textures, 16 px cube maps.
  EXPECT_GE(caps.max_texture_size_px, 64);
  EXPECT_GE(caps.max_cube_map_size_px, 16);
  // mediump must carry at least 10 mantissa bits (GLSL ES 1.00, 4.5.2).
  EXPECT_GE(caps.fragment_mediump_mantissa_bits, 10);
  if (caps.fragment_highp) {
    EXPECT_GE(caps.fragment_highp_mantissa_bits, 16);
  }
  if (caps.canRenderHalfFloat()) {
    EXPECT_TRUE(caps.texture_half_float);
  }
  EXPECT_NE(caps.summary().find(caps.renderer), std::string::npos);

  const gles::Capabilities plain = caps.withoutExtensions();
  EXPECT_FALSE(plain.canRenderHalfFloat());
  EXPECT_FALSE(plain.fragment_highp || plain.texture_float || plain.depth_texture || plain.egl_image_external);
  EXPECT_EQ(plain.max_texture_size_px, caps.max_texture_size_px);
  EXPECT_NE(plain.summary().find("maps: 8-bit"), std::string::npos);
  std::cout << "[ caps     ] " << caps.summary() << "\n";
}

TEST_F(GpuTest, MaskedCapabilitiesSelectThe8BitStorage) {
  std::string error;
  passes::EnvironmentMaps maps;
  ASSERT_TRUE(maps.init(test::sharedCapabilities().withoutExtensions(), {}, error)) << error;
  EXPECT_EQ(maps.storage(), passes::CubeStorage::kSrgb8);
}

TEST_F(GpuTest, ShaderCompileErrorNamesTheFileAndCarriesTheLog) {
  const std::string vertex = "attribute vec2 a_position;\nvoid main() { gl_Position = vec4(a_position, 0.0, 1.0); }\n";
  const std::string fragment = "void main() {\n  gl_FragColor = vec4(no_such_symbol);\n}\n";
  std::string error;
  auto program = gles::Program::fromSources("ok_test.vert", vertex, "broken_test.frag", fragment, "", error);
  EXPECT_FALSE(program.has_value());
  EXPECT_NE(error.find("broken_test.frag"), std::string::npos) << error;
  EXPECT_NE(error.find("no_such_symbol"), std::string::npos) << error;  // the driver's info log
  // The log's "N:line" prefix maps to the listed source number.
  EXPECT_NE(error.find("1=broken_test.frag"), std::string::npos) << error;
}

TEST_F(GpuTest, MissingEmbeddedShaderIsReportedByName) {
  std::string error;
  auto program = gles::Program::fromEmbedded("image_quad.vert", "does_not_exist.frag", "", error);
  EXPECT_FALSE(program.has_value());
  EXPECT_NE(error.find("does_not_exist.frag"), std::string::npos) << error;
}

TEST_F(GpuTest, EveryEmbeddedShaderProgramCompilesForBothStorages) {
  const auto& shaders = gles::embeddedShaders();
  ASSERT_TRUE(shaders.count("probe_to_cube.frag") && shaders.count("cosine_irradiance.frag"));
  for (const char* defines : {"", "#define CUBE_STORAGE_SRGB8 1\n"}) {
    std::string error;
    EXPECT_TRUE(gles::Program::fromEmbedded("probe_to_cube.vert", "probe_to_cube.frag", defines, error)) << error;
    for (const char* pass : {"#define PREFILTER_PASS 1\n", "#define EAST_PASS 1\n", "#define NORTH_PASS 1\n"}) {
      EXPECT_TRUE(gles::Program::fromEmbedded("cube_face.vert", "cosine_irradiance.frag", std::string(defines) + pass, error))
          << error;
    }
    EXPECT_TRUE(gles::Program::fromEmbedded("sphere_object.vert", "sphere_object.frag", defines, error)) << error;
  }
}

// color_transfer.glsl decodes sRGB's upper segment with a polynomial, not
// pow(): against pow() on the same GPU it must stay within the fit's bound
// (9.5e-5 relative, from the Chebyshev fit at double precision) plus the
// rounding of a dozen float operations and of llvmpipe's own pow (both under
// 1e-5), so 1.1e-4 in all; the lower, linear segment must be exact to
// rounding. The shader writes 0.5 + 1000 x relative error into a byte: one
// step is 3.9e-6, and a saturated byte (over 5e-4) fails the bound.
TEST_F(GpuTest, TheSrgbDecodeMatchesTheCurveAcrossItsRange) {
  constexpr int kSamples = 1024;
  const std::string vertex = "attribute vec2 a_position;\nvoid main() { gl_Position = vec4(a_position, 0.0, 1.0); }\n";
  const std::string fragment =
      "#include \"color_transfer.glsl\"\n"
      "uniform float u_samples;\n"
      "void main() {\n"
      "  float c = (gl_FragCoord.x - 0.5) / (u_samples - 1.0);\n"
      "  float decoded = srgbToLinear(vec3(c)).g;\n"
      "  float exact = c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);\n"
      "  float relative = c > 0.0 ? decoded / exact - 1.0 : decoded;\n"
      "  gl_FragColor = vec4(0.5 + 1000.0 * relative, 0.0, 0.0, 1.0);\n"
      "}\n";
  std::string error;
  auto program = gles::Program::fromSources("srgb_test.vert", vertex, "srgb_test.frag", fragment, "", error);
  ASSERT_TRUE(program.has_value()) << error;
  gles::RenderTarget target;
  ASSERT_TRUE(target.init(kSamples, 1, error)) << error;
  gles::FullScreenQuad quad;
  ASSERT_TRUE(quad.init(error)) << error;
  target.bind();
  program->use();
  glUniform1f(program->uniform("u_samples"), static_cast<float>(kSamples));
  quad.draw(program->attribute("a_position"));
  ImageRGB8 image;
  ASSERT_TRUE(target.readRGB(image, error)) << error;
  double worst_upper = 0.0, worst_lower = 0.0;
  for (int x = 0; x < kSamples; ++x) {
    const double c = static_cast<double>(x) / (kSamples - 1);
    const double relative = (image.row(0)[3 * x] / 255.0 - 0.5) / 1000.0;
    double& worst = c <= 0.04045 ? worst_lower : worst_upper;
    worst = std::max(worst, std::abs(relative));
  }
  std::printf("[ measure  ] sRGB decode against pow(): max relative error %.2e (upper segment), %.2e (lower)\n",
              worst_upper, worst_lower);
  EXPECT_LE(worst_upper, 1.1e-4);
  EXPECT_LE(worst_lower, 1e-5);
}

// The soak's GL object count is the driver's (glIs*), not our own tally:
// a bound texture and framebuffer are counted while they live, and not
// after their owners free them.
TEST_F(GpuTest, TheDriversObjectCountFollowsCreationAndDeletion) {
  const gles::GlObjectCounts before = gles::countLiveGlObjects();
  {
    std::string error;
    std::optional<gles::Texture> texture = gles::createTexture2D(4, 4, GL_RGBA, GL_UNSIGNED_BYTE, GL_NEAREST, nullptr, error);
    ASSERT_TRUE(texture.has_value()) << error;
    gles::Framebuffer framebuffer = gles::Framebuffer::create();
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer.id());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    const gles::GlObjectCounts during = gles::countLiveGlObjects();
    EXPECT_EQ(during.textures, before.textures + 1);
    EXPECT_EQ(during.framebuffers, before.framebuffers + 1);
    EXPECT_EQ(during.total(), before.total() + 2);
  }
  const gles::GlObjectCounts after = gles::countLiveGlObjects();
  EXPECT_EQ(after.textures, before.textures);
  EXPECT_EQ(after.framebuffers, before.framebuffers);
  EXPECT_EQ(after.total(), before.total());
}

TEST_F(GpuTest, RenderTargetReadsBackTopRowFirst) {
  std::string error;
  gles::RenderTarget target;
  ASSERT_TRUE(target.init(8, 6, error)) << error;
  target.bind();
  glClearColor(0.0f, 0.0f, 1.0f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  // Window y >= 3 is the upper half under GL's bottom-up window coordinates.
  glEnable(GL_SCISSOR_TEST);
  glScissor(0, 3, 8, 3);
  glClearColor(1.0f, 0.0f, 0.0f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
  ImageRGB8 image;
  ASSERT_TRUE(target.readRGB(image, error)) << error;
  ASSERT_EQ(image.width, 8);
  ASSERT_EQ(image.height, 6);
  EXPECT_EQ(image.row(0)[0], 255);  // top row: red
  EXPECT_EQ(image.row(0)[2], 0);
  EXPECT_EQ(image.row(5)[0], 0);  // bottom row: blue
  EXPECT_EQ(image.row(5)[2], 255);
}

TEST_F(GpuTest, RenderTargetRejectsEmptySizeWithAReason) {
  std::string error;
  gles::RenderTarget target;
  EXPECT_FALSE(target.init(0, 10, error));
  EXPECT_NE(error.find("0x10"), std::string::npos) << error;
}

}  // namespace
}  // namespace probelight

#include "gles/extension_list.hpp"

namespace probelight::gles {
namespace {

// A name that is a prefix of another listed name is not present.
TEST(ExtensionList, MatchesWholeNamesOnly) {
  const char* list = "GL_OES_texture_half_float_linear GL_OES_depth_texture";
  EXPECT_FALSE(hasExtension(list, "GL_OES_texture_half_float"));
  EXPECT_TRUE(hasExtension(list, "GL_OES_texture_half_float_linear"));
  EXPECT_TRUE(hasExtension(list, "GL_OES_depth_texture"));
  EXPECT_FALSE(hasExtension(list, "GL_OES_depth"));
  EXPECT_FALSE(hasExtension(nullptr, "GL_OES_depth_texture"));
  EXPECT_TRUE(hasExtension("GL_OES_texture_half_float_linear GL_OES_texture_half_float", "GL_OES_texture_half_float"));
}

// GL_VERSION as GLES gives it ("OpenGL ES N.M vendor"); anything else
// leaves the GLES2 defaults.
TEST(GlesVersion, ReadsMajorAndMinorFromTheVersionString) {
  int major = 2, minor = 0;
  EXPECT_TRUE(parseGlesVersion("OpenGL ES 3.2 Mesa 22.3.6", major, minor));
  EXPECT_EQ(major, 3);
  EXPECT_EQ(minor, 2);
  EXPECT_TRUE(parseGlesVersion("OpenGL ES 2.0 V3D 4.2", major, minor));
  EXPECT_EQ(major, 2);
  EXPECT_EQ(minor, 0);
  for (const char* not_gles : {"4.6 (Core Profile) Mesa 22.3.6", "OpenGL ES", "OpenGL ES 3", "OpenGL ES x.1", ""}) {
    major = 7;
    minor = 7;
    EXPECT_FALSE(parseGlesVersion(not_gles, major, minor)) << not_gles;
    EXPECT_EQ(major, 7) << not_gles;
    EXPECT_EQ(minor, 7) << not_gles;
  }
}

// The half-float route for each context the kiosk meets: ES 3 with
// EXT_color_buffer_float takes sized RGBA16F and ES 3's GL_HALF_FLOAT (V3D
// has no EXT_color_buffer_half_float); ES 2 needs both OES extensions and
// takes the unsized GL_RGBA with GL_HALF_FLOAT_OES; else none, saying
// which extension is missing.
TEST(HalfFloatRoute, FollowsTheContextsVersionAndExtensions) {
  Capabilities pi4;
  pi4.gles_major_version = 3;
  pi4.gles_minor_version = 1;
  pi4.texture_half_float = true;
  pi4.color_buffer_float = true;
  ASSERT_TRUE(pi4.halfFloatRenderFormat().has_value());
  EXPECT_EQ(pi4.halfFloatRenderFormat()->internal_format, kGlRgba16f);
  EXPECT_EQ(pi4.halfFloatRenderFormat()->type, kGlHalfFloat);
  EXPECT_EQ(pi4.halfFloatRoute(), "RGBA16F: ES 3.1 with EXT_color_buffer_float");

  Capabilities es2 = pi4;
  es2.gles_major_version = 2;
  es2.gles_minor_version = 0;
  EXPECT_FALSE(es2.canRenderHalfFloat()) << "EXT_color_buffer_float is an ES 3 extension";
  EXPECT_EQ(es2.halfFloatRoute(), "ES 2.0 without EXT_color_buffer_half_float");
  es2.color_buffer_half_float = true;
  ASSERT_TRUE(es2.halfFloatRenderFormat().has_value());
  EXPECT_EQ(es2.halfFloatRenderFormat()->internal_format, GL_RGBA);
  EXPECT_EQ(es2.halfFloatRenderFormat()->type, static_cast<GLenum>(GL_HALF_FLOAT_OES));

  Capabilities es3_without = pi4;
  es3_without.color_buffer_float = false;
  es3_without.texture_half_float = false;
  EXPECT_FALSE(es3_without.canRenderHalfFloat());
  EXPECT_EQ(es3_without.halfFloatRoute(),
            "ES 3.1 without EXT_color_buffer_float, OES_texture_half_float, EXT_color_buffer_half_float");
  EXPECT_FALSE(pi4.withoutExtensions().canRenderHalfFloat());
  EXPECT_EQ(pi4.withoutExtensions().gles_major_version, 2);
}

}  // namespace
}  // namespace probelight::gles
