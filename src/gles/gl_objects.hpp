// RAII owners of GLES2 objects and the shader program builder. All of them
// must be created and destroyed with the owning context current.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <GLES2/gl2.h>
#include <GLES2/gl2ext.h>

namespace probelight::gles {

// "GL_INVALID_ENUM (0x0500)".
std::string glErrorName(GLenum code);
// Drains glGetError. Returns false, with "<call> failed: GL_..." in `error`,
// when any error was pending, so the failing call is named in the message.
bool checkGl(const char* call, std::string& error);

// Move-only owner of one GL name; `Deleter` frees it.
template <void (*Deleter)(GLuint)>
class GlName {
 public:
  GlName() = default;
  explicit GlName(GLuint name) : name_(name) {}
  ~GlName() { reset(); }
  GlName(GlName&& other) noexcept : name_(std::exchange(other.name_, 0)) {}
  GlName& operator=(GlName&& other) noexcept {
    if (this != &other) {
      reset();
      name_ = std::exchange(other.name_, 0);
    }
    return *this;
  }
  GlName(const GlName&) = delete;
  GlName& operator=(const GlName&) = delete;

  GLuint id() const { return name_; }
  bool valid() const { return name_ != 0; }
  void reset() {
    if (name_ != 0) Deleter(name_);
    name_ = 0;
  }

 private:
  GLuint name_ = 0;
};

namespace detail {
void deleteTexture(GLuint name);
void deleteFramebuffer(GLuint name);
void deleteRenderbuffer(GLuint name);
void deleteBuffer(GLuint name);
void deleteProgram(GLuint name);
}  // namespace detail

class Texture : public GlName<detail::deleteTexture> {
 public:
  using GlName::GlName;
  static Texture create();  // glGenTextures
};
class Framebuffer : public GlName<detail::deleteFramebuffer> {
 public:
  using GlName::GlName;
  static Framebuffer create();
};
class Renderbuffer : public GlName<detail::deleteRenderbuffer> {
 public:
  using GlName::GlName;
  static Renderbuffer create();
};
class Buffer : public GlName<detail::deleteBuffer> {
 public:
  using GlName::GlName;
  static Buffer create();
};

// The driver's own count of the GL objects alive in the current context,
// for leak checks over long runs (the soak): every name up to the highest
// one this process was given (glGen*, glCreateProgram, glCreateShader) is
// asked with glIs*. A leak shows as a count that grows. A name generated
// but never bound is not yet an object, and is not counted.
struct GlObjectCounts {
  int textures = 0, framebuffers = 0, renderbuffers = 0, buffers = 0, programs = 0, shaders = 0;
  int total() const { return textures + framebuffers + renderbuffers + buffers + programs + shaders; }
};
GlObjectCounts countLiveGlObjects();

// Allocates a 2D texture with the given filter and CLAMP_TO_EDGE wrap.
// `type` GL_UNSIGNED_BYTE or GL_HALF_FLOAT_OES; `pixels` may be null. The
// internal format is `format` (GLES2's unsized formats) unless given: ES 3's
// sized GL_RGBA16F (Capabilities::halfFloatRenderFormat).
std::optional<Texture> createTexture2D(int width, int height, GLenum format, GLenum type, GLint filter,
                                       const void* pixels, std::string& error);
std::optional<Texture> createTexture2D(int width, int height, GLint internal_format, GLenum format, GLenum type,
                                       GLint filter, const void* pixels, std::string& error);
// Allocates the six faces of a square cube map, NEAREST filtering, CLAMP_TO_EDGE.
std::optional<Texture> createCubeTexture(int face_size, GLenum format, GLenum type, std::string& error);
std::optional<Texture> createCubeTexture(int face_size, GLint internal_format, GLenum format, GLenum type,
                                         std::string& error);

// Describes why a framebuffer is incomplete, e.g. "GL_FRAMEBUFFER_UNSUPPORTED".
std::string framebufferStatusName(GLenum status);

// For benchmarks only: while set, every program built from embedded files
// gets this function's fragment shader instead of its own, when it returns
// one (it is given the file's name, the defines and the file's source). The
// bench uses it for a stage's limit: the same passes, targets and draws with
// a trivial shader that makes as many texture reads.
using FragmentShaderSubstitute =
    std::function<std::optional<std::string>(std::string_view fragment_file, std::string_view defines,
                                             std::string_view source)>;
void setFragmentShaderSubstitute(FragmentShaderSubstitute substitute);

// A linked vertex + fragment program. Sources are the embedded files of
// shaders-gles/; a line `#include "name.glsl"` pulls in another embedded file.
// Every fragment shader gets the precision prelude (highp where the GPU has
// it in fragment shaders, mediump otherwise) and `defines` after `#version 100`.
class Program : public GlName<detail::deleteProgram> {
 public:
  using GlName::GlName;

  static std::optional<Program> fromEmbedded(std::string_view vertex_file, std::string_view fragment_file,
                                             std::string_view defines, std::string& error);
  // Same, for sources not among the embedded files (tests, tools). The names
  // only label error messages.
  static std::optional<Program> fromSources(std::string_view vertex_name, std::string_view vertex_source,
                                            std::string_view fragment_name, std::string_view fragment_source,
                                            std::string_view defines, std::string& error);

  void use() const { glUseProgram(id()); }
  // -1 when the program has no such active uniform/attribute (the compiler
  // may drop unused ones; setting -1 is a harmless no-op in GL).
  GLint uniform(const char* name) const { return glGetUniformLocation(id(), name); }
  GLint attribute(const char* name) const { return glGetAttribLocation(id(), name); }
};

// Position-only full-screen quad (triangle strip, 4 vertices, vec2 in [-1, 1])
// shared by the full-screen passes.
class FullScreenQuad {
 public:
  bool init(std::string& error);
  // Binds the quad to `position_attribute` and draws it.
  void draw(GLint position_attribute) const;

 private:
  Buffer vertices_;
};

}  // namespace probelight::gles
