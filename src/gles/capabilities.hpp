// What the current GLES2 context can do, probed at run time. Stages choose
// their storage formats from this, never from the GL version string (Mesa
// reports ES 3.2 even for an ES 2 request; the board's GPU does not).
#pragma once

#include <optional>
#include <string>

#include <GLES2/gl2.h>
#include <GLES2/gl2ext.h>

namespace probelight::gles {

// How this context stores linear half floats in a texture it can also
// render to. GLES2's extensions allocate an unsized GL_RGBA texture of type
// GL_HALF_FLOAT_OES; ES 3 allocates the sized GL_RGBA16F, and then the type
// must be ES 3's GL_HALF_FLOAT (a sized format refuses the OES enum).
struct HalfFloatFormat {
  GLint internal_format = GL_RGBA;
  GLenum type = GL_HALF_FLOAT_OES;
};

// ES 3.0 enums, for the sized half-float path in an ES 3 context; the GLES2
// headers we compile against do not define them.
inline constexpr GLint kGlRgba16f = 0x881A;   // GL_RGBA16F
inline constexpr GLenum kGlHalfFloat = 0x140B;  // GL_HALF_FLOAT

struct Capabilities {
  // The context's OpenGL ES version, from GL_VERSION ("OpenGL ES 3.2 ...").
  // The kiosk asks for ES 3 where the display offers it and ES 2 otherwise;
  // its shaders are GLSL ES 1.00 either way.
  int gles_major_version = 2;
  int gles_minor_version = 0;
  bool texture_half_float = false;         // GL_OES_texture_half_float
  bool texture_half_float_linear = false;  // GL_OES_texture_half_float_linear
  bool color_buffer_half_float = false;    // GL_EXT_color_buffer_half_float
  bool texture_float = false;              // GL_OES_texture_float
  bool color_buffer_float = false;         // GL_EXT_color_buffer_float
  bool depth_texture = false;              // GL_OES_depth_texture
  bool egl_image_external = false;         // GL_OES_EGL_image_external
  bool standard_derivatives = false;       // GL_OES_standard_derivatives
  bool unpack_subimage = false;            // GL_EXT_unpack_subimage (GL_UNPACK_ROW_LENGTH)
  bool element_index_uint = false;         // GL_OES_element_index_uint (32-bit indices)
  bool texture_npot = false;               // GL_OES_texture_npot (mipmaps and REPEAT on any size)
  bool egl_dmabuf_import = false;          // EGL_EXT_image_dma_buf_import on the current display
  bool fragment_highp = false;             // highp float exists in fragment shaders
  int fragment_highp_mantissa_bits = 0;    // 23 for IEEE single; 0 when absent
  int fragment_mediump_mantissa_bits = 0;  // 10 for IEEE half
  int max_texture_size_px = 0;
  int max_cube_map_size_px = 0;
  int max_fragment_texture_units = 8;      // GL_MAX_TEXTURE_IMAGE_UNITS; GLES2 guarantees 8
  int max_fragment_uniform_vectors = 16;   // GL_MAX_FRAGMENT_UNIFORM_VECTORS; GLES2 guarantees 16
  int max_renderbuffer_size_px = 0;        // GL_MAX_RENDERBUFFER_SIZE
  int max_viewport_px = 0;                 // the smaller of GL_MAX_VIEWPORT_DIMS
  // Anti-aliased model edges (passes/edge_antialiasing.hpp). The EXT lets a
  // single-sampled texture be rendered with N samples that the GPU resolves
  // on its way out of tile memory (tilers: Mali, Adreno, PowerVR): MSAA at
  // little more than the cost of a plain pass. Set only when the extension
  // is listed and both entry points resolve, so a caller may call them.
  bool multisampled_render_to_texture = false;  // GL_EXT_multisampled_render_to_texture
  int max_samples = 0;                          // GL_MAX_SAMPLES_EXT with the EXT; 0 without
  PFNGLRENDERBUFFERSTORAGEMULTISAMPLEEXTPROC renderbuffer_storage_multisample = nullptr;
  PFNGLFRAMEBUFFERTEXTURE2DMULTISAMPLEEXTPROC framebuffer_texture_2d_multisample = nullptr;
  // EGL_SAMPLES of the current context's config: the multisampling of a
  // window surface drawn directly (the kiosk draws into FBOs, so this is for
  // the log; a draw checks the bound framebuffer's GL_SAMPLES instead).
  int egl_config_samples = 0;
  std::string renderer;  // GL_RENDERER
  std::string version;   // GL_VERSION

  // Stages may store linear half floats only when they can both sample and
  // render them; otherwise they use the 8-bit path. An ES 3 context renders
  // sized RGBA16F with EXT_color_buffer_float (V3D, the Pi 4's GPU, offers
  // only that: no EXT_color_buffer_half_float); an ES 2 context needs
  // OES_texture_half_float and EXT_color_buffer_half_float.
  std::optional<HalfFloatFormat> halfFloatRenderFormat() const;
  bool canRenderHalfFloat() const { return halfFloatRenderFormat().has_value(); }
  // Which of those routes the maps take, or why none: for the start-up line.
  std::string halfFloatRoute() const;
  // A copy with every optional extension and fragment highp cleared, the
  // version cut to ES 2.0 and the texture units to GLES2's minimum of 8, to
  // run (and test) the plain 8-bit, mediump-declared path on any GPU.
  Capabilities withoutExtensions() const;
  // One line for logs: renderer, version, precision and extension flags.
  std::string summary() const;
};

// Queries the context current on this thread.
Capabilities probeCapabilities();
// "OpenGL ES 3.2 Mesa 22.3.6" -> 3, 2. False, and both left alone, for a
// string that is not a GLES version (then the GLES2 defaults stand).
bool parseGlesVersion(const std::string& gl_version, int& major, int& minor);

}  // namespace probelight::gles
