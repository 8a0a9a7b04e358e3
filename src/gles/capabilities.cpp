#include "gles/capabilities.hpp"
#include "gles/extension_list.hpp"

#include <algorithm>
#include <cstring>
#include <string_view>

#include <EGL/egl.h>
#include <GLES2/gl2.h>

namespace probelight::gles {

namespace {

std::string glString(GLenum name) {
  const auto* text = reinterpret_cast<const char*>(glGetString(name));
  return text != nullptr ? text : "";
}

// EGL_SAMPLES of the config the current context was made with (0 when it
// cannot be told: no context, or a config-less one).
int currentConfigSamples(EGLDisplay display) {
  const EGLContext context = eglGetCurrentContext();
  EGLint config_id = 0;
  if (context == EGL_NO_CONTEXT || !eglQueryContext(display, context, EGL_CONFIG_ID, &config_id)) return 0;
  const EGLint attributes[] = {EGL_CONFIG_ID, config_id, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  EGLint samples = 0;
  if (!eglChooseConfig(display, attributes, &config, 1, &count) || count < 1 ||
      !eglGetConfigAttrib(display, config, EGL_SAMPLES, &samples))
    return 0;
  return samples;
}

}  // namespace

bool parseGlesVersion(const std::string& gl_version, int& major, int& minor) {
  // GLES: "OpenGL ES N.M<space><vendor-specific information>" (ES 2.0
  // section 6.1.5; ES 3.2 section 20.2).
  static constexpr std::string_view kPrefix = "OpenGL ES ";
  if (gl_version.compare(0, kPrefix.size(), kPrefix) != 0) return false;
  std::size_t at = kPrefix.size();
  auto number = [&](int& value) {
    const std::size_t from = at;
    value = 0;
    while (at < gl_version.size() && gl_version[at] >= '0' && gl_version[at] <= '9' && at - from < 3)
      value = value * 10 + (gl_version[at++] - '0');
    return at > from;
  };
  int parsed_major = 0, parsed_minor = 0;
  if (!number(parsed_major) || at >= gl_version.size() || gl_version[at++] != '.' || !number(parsed_minor)) return false;
  major = parsed_major;
  minor = parsed_minor;
  return true;
}

Capabilities probeCapabilities() {
  Capabilities caps;
  const auto* extensions = reinterpret_cast<const char*>(glGetString(GL_EXTENSIONS));
  caps.texture_half_float = hasExtension(extensions, "GL_OES_texture_half_float");
  caps.texture_half_float_linear = hasExtension(extensions, "GL_OES_texture_half_float_linear");
  caps.color_buffer_half_float = hasExtension(extensions, "GL_EXT_color_buffer_half_float");
  caps.texture_float = hasExtension(extensions, "GL_OES_texture_float");
  caps.color_buffer_float = hasExtension(extensions, "GL_EXT_color_buffer_float");
  caps.depth_texture = hasExtension(extensions, "GL_OES_depth_texture");
  caps.egl_image_external = hasExtension(extensions, "GL_OES_EGL_image_external");
  caps.standard_derivatives = hasExtension(extensions, "GL_OES_standard_derivatives");
  caps.unpack_subimage = hasExtension(extensions, "GL_EXT_unpack_subimage");
  caps.element_index_uint = hasExtension(extensions, "GL_OES_element_index_uint");
  caps.texture_npot = hasExtension(extensions, "GL_OES_texture_npot");
  if (const EGLDisplay display = eglGetCurrentDisplay(); display != EGL_NO_DISPLAY) {
    caps.egl_dmabuf_import = hasExtension(eglQueryString(display, EGL_EXTENSIONS), "EGL_EXT_image_dma_buf_import");
    caps.egl_config_samples = currentConfigSamples(display);
  }
  // eglGetProcAddress may hand out a stub for any name (Mesa does, for
  // extensions it does not offer), so the extension string decides and the
  // pointers only confirm.
  if (hasExtension(extensions, "GL_EXT_multisampled_render_to_texture")) {
    caps.renderbuffer_storage_multisample = reinterpret_cast<PFNGLRENDERBUFFERSTORAGEMULTISAMPLEEXTPROC>(
        eglGetProcAddress("glRenderbufferStorageMultisampleEXT"));
    caps.framebuffer_texture_2d_multisample = reinterpret_cast<PFNGLFRAMEBUFFERTEXTURE2DMULTISAMPLEEXTPROC>(
        eglGetProcAddress("glFramebufferTexture2DMultisampleEXT"));
    if (caps.renderbuffer_storage_multisample != nullptr && caps.framebuffer_texture_2d_multisample != nullptr) {
      caps.multisampled_render_to_texture = true;
      // Only asked with the EXT: a plain GLES2 context rejects the enum.
      glGetIntegerv(GL_MAX_SAMPLES_EXT, &caps.max_samples);
    } else {
      caps.renderbuffer_storage_multisample = nullptr;
      caps.framebuffer_texture_2d_multisample = nullptr;
    }
  }

  GLint range[2] = {0, 0};
  GLint precision = 0;
  glGetShaderPrecisionFormat(GL_FRAGMENT_SHADER, GL_HIGH_FLOAT, range, &precision);
  // GLES2 reports range and precision 0 when highp is unsupported in fragment shaders.
  caps.fragment_highp = precision > 0;
  caps.fragment_highp_mantissa_bits = precision;
  glGetShaderPrecisionFormat(GL_FRAGMENT_SHADER, GL_MEDIUM_FLOAT, range, &precision);
  caps.fragment_mediump_mantissa_bits = precision;

  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &caps.max_texture_size_px);
  glGetIntegerv(GL_MAX_CUBE_MAP_TEXTURE_SIZE, &caps.max_cube_map_size_px);
  glGetIntegerv(GL_MAX_TEXTURE_IMAGE_UNITS, &caps.max_fragment_texture_units);
  glGetIntegerv(GL_MAX_FRAGMENT_UNIFORM_VECTORS, &caps.max_fragment_uniform_vectors);
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &caps.max_renderbuffer_size_px);
  GLint viewport_dims[2] = {0, 0};
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, viewport_dims);
  caps.max_viewport_px = std::min(viewport_dims[0], viewport_dims[1]);
  caps.renderer = glString(GL_RENDERER);
  caps.version = glString(GL_VERSION);
  parseGlesVersion(caps.version, caps.gles_major_version, caps.gles_minor_version);
  return caps;
}

std::optional<HalfFloatFormat> Capabilities::halfFloatRenderFormat() const {
  if (gles_major_version >= 3 && color_buffer_float) return HalfFloatFormat{kGlRgba16f, kGlHalfFloat};
  if (texture_half_float && color_buffer_half_float) return HalfFloatFormat{GL_RGBA, GL_HALF_FLOAT_OES};
  return std::nullopt;
}

std::string Capabilities::halfFloatRoute() const {
  const std::string es = "ES " + std::to_string(gles_major_version) + "." + std::to_string(gles_minor_version);
  if (gles_major_version >= 3 && color_buffer_float) return "RGBA16F: " + es + " with EXT_color_buffer_float";
  if (texture_half_float && color_buffer_half_float)
    return "RGBA half float: " + es + " with OES_texture_half_float and EXT_color_buffer_half_float";
  std::string missing;
  auto lacks = [&missing](bool present, const char* name) {
    if (present) return;
    missing += missing.empty() ? " without " : ", ";
    missing += name;
  };
  if (gles_major_version >= 3) lacks(color_buffer_float, "EXT_color_buffer_float");
  lacks(texture_half_float, "OES_texture_half_float");
  lacks(color_buffer_half_float, "EXT_color_buffer_half_float");
  return es + missing;
}

Capabilities Capabilities::withoutExtensions() const {
  Capabilities plain;
  plain.fragment_mediump_mantissa_bits = fragment_mediump_mantissa_bits;
  plain.max_texture_size_px = max_texture_size_px;
  plain.max_cube_map_size_px = max_cube_map_size_px;
  plain.max_fragment_texture_units = std::min(8, max_fragment_texture_units);
  plain.max_fragment_uniform_vectors = max_fragment_uniform_vectors;
  plain.max_renderbuffer_size_px = max_renderbuffer_size_px;
  plain.max_viewport_px = max_viewport_px;
  plain.egl_config_samples = egl_config_samples;  // the surface's, not an extension
  plain.gles_major_version = 2;
  plain.gles_minor_version = 0;
  plain.renderer = renderer + " [extensions masked]";
  plain.version = version;
  return plain;
}

std::string Capabilities::summary() const {
  std::string text = renderer + " | " + version + " | fragment highp " +
                     (fragment_highp ? std::to_string(fragment_highp_mantissa_bits) + " bits" : std::string("no")) +
                     ", mediump " + std::to_string(fragment_mediump_mantissa_bits) + " bits | max tex " +
                     std::to_string(max_texture_size_px) + ", cube " + std::to_string(max_cube_map_size_px) + ", units " +
                     std::to_string(max_fragment_texture_units) + ", frag uniforms " +
                     std::to_string(max_fragment_uniform_vectors) + ", EGL config samples " +
                     std::to_string(egl_config_samples) + " |";
  auto flag = [&text](bool on, const char* name) {
    text += on ? " +" : " -";
    text += name;
  };
  flag(texture_half_float, "half_float");
  flag(texture_half_float_linear, "half_float_linear");
  flag(color_buffer_half_float, "cb_half_float");
  flag(texture_float, "float");
  flag(color_buffer_float, "cb_float");
  flag(depth_texture, "depth_texture");
  flag(egl_image_external, "egl_image_external");
  flag(standard_derivatives, "derivatives");
  flag(unpack_subimage, "unpack_subimage");
  flag(element_index_uint, "index_uint");
  flag(texture_npot, "npot");
  flag(egl_dmabuf_import, "dmabuf_import");
  flag(multisampled_render_to_texture, "msaa_render_to_texture");
  if (multisampled_render_to_texture) text += " (" + std::to_string(max_samples) + " samples)";
  text += (canRenderHalfFloat() ? " | maps: half float (" : " | maps: 8-bit (") + halfFloatRoute() + ")";
  return text;
}

}  // namespace probelight::gles
