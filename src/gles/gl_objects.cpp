#include "gles/gl_objects.hpp"

#include <atomic>
#include <cstdio>

#include "gles/embedded_shaders.hpp"

namespace probelight::gles {

std::string glErrorName(GLenum code) {
  const char* name = "unknown GL error";
  switch (code) {
    case GL_NO_ERROR: name = "GL_NO_ERROR"; break;
    case GL_INVALID_ENUM: name = "GL_INVALID_ENUM"; break;
    case GL_INVALID_VALUE: name = "GL_INVALID_VALUE"; break;
    case GL_INVALID_OPERATION: name = "GL_INVALID_OPERATION"; break;
    case GL_INVALID_FRAMEBUFFER_OPERATION: name = "GL_INVALID_FRAMEBUFFER_OPERATION"; break;
    case GL_OUT_OF_MEMORY: name = "GL_OUT_OF_MEMORY"; break;
    default: break;
  }
  char text[64];
  std::snprintf(text, sizeof text, "%s (0x%04X)", name, code);
  return text;
}

bool checkGl(const char* call, std::string& error) {
  GLenum first = glGetError();
  if (first == GL_NO_ERROR) return true;
  // GL keeps one flag per error kind; drain them so the next check is clean.
  for (int i = 0; i < 16 && glGetError() != GL_NO_ERROR; ++i) {
  }
  error = std::string(call) + " failed: " + glErrorName(first);
  return false;
}

namespace detail {
void deleteTexture(GLuint name) { glDeleteTextures(1, &name); }
void deleteFramebuffer(GLuint name) { glDeleteFramebuffers(1, &name); }
void deleteRenderbuffer(GLuint name) { glDeleteRenderbuffers(1, &name); }
void deleteBuffer(GLuint name) { glDeleteBuffers(1, &name); }
void deleteProgram(GLuint name) { glDeleteProgram(name); }
}  // namespace detail

namespace {

// The highest GL name handed to this process: countLiveGlObjects' range.
std::atomic<GLuint> highest_name{0};

GLuint noteName(GLuint name) {
  GLuint seen = highest_name.load();
  while (name > seen && !highest_name.compare_exchange_weak(seen, name)) {
  }
  return name;
}

}  // namespace

Texture Texture::create() {
  GLuint name = 0;
  glGenTextures(1, &name);
  return Texture(noteName(name));
}
Framebuffer Framebuffer::create() {
  GLuint name = 0;
  glGenFramebuffers(1, &name);
  return Framebuffer(noteName(name));
}
Renderbuffer Renderbuffer::create() {
  GLuint name = 0;
  glGenRenderbuffers(1, &name);
  return Renderbuffer(noteName(name));
}
Buffer Buffer::create() {
  GLuint name = 0;
  glGenBuffers(1, &name);
  return Buffer(noteName(name));
}

GlObjectCounts countLiveGlObjects() {
  GlObjectCounts counts;
  const GLuint last = highest_name.load();
  for (GLuint name = 1; name <= last; ++name) {
    counts.textures += glIsTexture(name) ? 1 : 0;
    counts.framebuffers += glIsFramebuffer(name) ? 1 : 0;
    counts.renderbuffers += glIsRenderbuffer(name) ? 1 : 0;
    counts.buffers += glIsBuffer(name) ? 1 : 0;
    counts.programs += glIsProgram(name) ? 1 : 0;
    counts.shaders += glIsShader(name) ? 1 : 0;
  }
  return counts;
}

std::optional<Texture> createTexture2D(int width, int height, GLenum format, GLenum type, GLint filter,
                                       const void* pixels, std::string& error) {
  return createTexture2D(width, height, static_cast<GLint>(format), format, type, filter, pixels, error);
}

std::optional<Texture> createTexture2D(int width, int height, GLint internal_format, GLenum format, GLenum type,
                                       GLint filter, const void* pixels, std::string& error) {
  Texture texture = Texture::create();
  glBindTexture(GL_TEXTURE_2D, texture.id());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, internal_format, width, height, 0, format, type, pixels);
  if (!checkGl("glTexImage2D(GL_TEXTURE_2D)", error)) {
    error += " for a " + std::to_string(width) + "x" + std::to_string(height) + " texture";
    return std::nullopt;
  }
  return texture;
}

std::optional<Texture> createCubeTexture(int face_size, GLenum format, GLenum type, std::string& error) {
  return createCubeTexture(face_size, static_cast<GLint>(format), format, type, error);
}

std::optional<Texture> createCubeTexture(int face_size, GLint internal_format, GLenum format, GLenum type,
                                         std::string& error) {
  Texture texture = Texture::create();
  glBindTexture(GL_TEXTURE_CUBE_MAP, texture.id());
  glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  for (int face = 0; face < 6; ++face) {
    glTexImage2D(GL_TEXTURE_CUBE_MAP_POSITIVE_X + static_cast<GLenum>(face), 0, internal_format, face_size, face_size,
                 0, format, type, nullptr);
  }
  if (!checkGl("glTexImage2D(GL_TEXTURE_CUBE_MAP_*)", error)) {
    error += " for a cube map of " + std::to_string(face_size) + " px faces";
    return std::nullopt;
  }
  return texture;
}

std::string framebufferStatusName(GLenum status) {
  switch (status) {
    case GL_FRAMEBUFFER_COMPLETE: return "GL_FRAMEBUFFER_COMPLETE";
    case GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT: return "GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT";
    case GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT: return "GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT";
    case GL_FRAMEBUFFER_INCOMPLETE_DIMENSIONS: return "GL_FRAMEBUFFER_INCOMPLETE_DIMENSIONS";
    case GL_FRAMEBUFFER_UNSUPPORTED: return "GL_FRAMEBUFFER_UNSUPPORTED";
    default: {
      char text[48];
      std::snprintf(text, sizeof text, "framebuffer status 0x%04X", status);
      return text;
    }
  }
}

namespace {

constexpr std::string_view kVertexPrelude = "#version 100\nprecision highp float;\n";
// Fragment shaders get highp only where the GPU has it (GLES2 makes it
// optional there); shaders check PL_FRAGMENT_HIGHP where precision matters.
constexpr std::string_view kFragmentPrelude =
    "#version 100\n"
    "#ifdef GL_FRAGMENT_PRECISION_HIGH\n"
    "precision highp float;\n"
    "#define PL_FRAGMENT_HIGHP 1\n"
    "#else\n"
    "precision mediump float;\n"
    "#endif\n";

// Expands `#include "file"` lines from the embedded shaders. Each file gets
// its own GLSL source-string number through `#line 1 N`, so compiler messages
// such as "2:14(3): error" can be mapped back to labels[2].
bool expandIncludes(std::string_view file_name, std::string_view source, int depth, std::vector<std::string>& labels,
                    std::string& out, std::string& extensions, std::string& error) {
  const int source_number = static_cast<int>(labels.size());
  labels.emplace_back(file_name);
  out += "#line 1 " + std::to_string(source_number) + "\n";
  int line_number = 0;
  size_t start = 0;
  while (start <= source.size()) {
    size_t end = source.find('\n', start);
    if (end == std::string_view::npos) end = source.size();
    std::string_view line = source.substr(start, end - start);
    ++line_number;
    const size_t first = line.find_first_not_of(" \t");
    std::string_view trimmed = first == std::string_view::npos ? std::string_view{} : line.substr(first);
    if (trimmed.rfind("#version", 0) == 0) {
      out += "\n";  // the prelude already put #version first; keep line numbers
    } else if (trimmed.rfind("#extension", 0) == 0) {
      // GLSL ES wants #extension before any other token, so it goes up
      // above the prelude's precision statements.
      extensions += std::string(trimmed) + "\n";
      out += "\n";
    } else if (trimmed.rfind("#include", 0) == 0) {
      const size_t open = trimmed.find('"');
      const size_t close = open == std::string_view::npos ? open : trimmed.find('"', open + 1);
      if (close == std::string_view::npos) {
        error = std::string(file_name) + ":" + std::to_string(line_number) + ": malformed #include, expected #include \"name.glsl\"";
        return false;
      }
      const std::string_view included = trimmed.substr(open + 1, close - open - 1);
      const auto& shaders = embeddedShaders();
      const auto found = shaders.find(included);
      if (found == shaders.end()) {
        error = std::string(file_name) + ":" + std::to_string(line_number) + ": #include \"" + std::string(included) +
                "\" is not among the embedded shaders (is it in shaders-gles/ and was CMake re-run?)";
        return false;
      }
      if (depth > 4) {
        error = std::string(file_name) + ": #include nested too deeply (a cycle?)";
        return false;
      }
      if (!expandIncludes(included, found->second, depth + 1, labels, out, extensions, error)) return false;
      out += "#line " + std::to_string(line_number + 1) + " " + std::to_string(source_number) + "\n";
    } else {
      out += line;
      out += "\n";
    }
    start = end + 1;
  }
  return true;
}

std::string describeSources(const std::vector<std::string>& labels) {
  std::string text = "source numbers:";
  for (size_t i = 0; i < labels.size(); ++i) {
    text.append(" ").append(std::to_string(i)).append("=").append(labels[i]);
  }
  return text;
}

GLuint compileShader(GLenum stage, std::string_view file_name, std::string_view source, std::string_view defines,
                     std::string& error) {
  const bool fragment = stage == GL_FRAGMENT_SHADER;
  // Source number 0 is the prelude; the shader's own file starts at 1.
  std::vector<std::string> labels{"<prelude>"};
  std::string body, extensions;
  if (!expandIncludes(file_name, source, 0, labels, body, extensions, error)) return 0;
  std::string_view prelude = fragment ? kFragmentPrelude : kVertexPrelude;
  const std::string_view version_line = "#version 100\n";
  std::string text(version_line);
  text += extensions;
  text += prelude.substr(version_line.size());
  text += defines;
  text += "\n";
  text += body;
  GLuint shader = noteName(glCreateShader(stage));
  const char* pointer = text.c_str();
  glShaderSource(shader, 1, &pointer, nullptr);
  glCompileShader(shader);
  GLint compiled = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &compiled);
  if (compiled != GL_TRUE) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<size_t>(length > 1 ? length : 1), '\0');
    glGetShaderInfoLog(shader, length, nullptr, log.data());
    error = std::string(fragment ? "fragment" : "vertex") + " shader " + std::string(file_name) +
            " failed to compile (" + describeSources(labels) + "):\n" + log.c_str();
    glDeleteShader(shader);
    return 0;
  }
  return shader;
}

}  // namespace

std::optional<Program> Program::fromSources(std::string_view vertex_name, std::string_view vertex_source,
                                            std::string_view fragment_name, std::string_view fragment_source,
                                            std::string_view defines, std::string& error) {
  const GLuint vertex = compileShader(GL_VERTEX_SHADER, vertex_name, vertex_source, defines, error);
  if (vertex == 0) return std::nullopt;
  const GLuint fragment = compileShader(GL_FRAGMENT_SHADER, fragment_name, fragment_source, defines, error);
  if (fragment == 0) {
    glDeleteShader(vertex);
    return std::nullopt;
  }
  Program program(noteName(glCreateProgram()));
  glAttachShader(program.id(), vertex);
  glAttachShader(program.id(), fragment);
  // Attribute 0 must be enabled on some GLES2 drivers; bind "a_position" there.
  glBindAttribLocation(program.id(), 0, "a_position");
  glLinkProgram(program.id());
  glDeleteShader(vertex);
  glDeleteShader(fragment);
  GLint linked = GL_FALSE;
  glGetProgramiv(program.id(), GL_LINK_STATUS, &linked);
  if (linked != GL_TRUE) {
    GLint length = 0;
    glGetProgramiv(program.id(), GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<size_t>(length > 1 ? length : 1), '\0');
    glGetProgramInfoLog(program.id(), length, nullptr, log.data());
    error = "program " + std::string(vertex_name) + " + " + std::string(fragment_name) + " failed to link:\n" + log.c_str();
    return std::nullopt;
  }
  if (!checkGl("glLinkProgram", error)) return std::nullopt;
  return program;
}

namespace {
FragmentShaderSubstitute& fragmentShaderSubstitute() {
  static FragmentShaderSubstitute substitute;
  return substitute;
}
}  // namespace

void setFragmentShaderSubstitute(FragmentShaderSubstitute substitute) {
  fragmentShaderSubstitute() = std::move(substitute);
}

std::optional<Program> Program::fromEmbedded(std::string_view vertex_file, std::string_view fragment_file,
                                             std::string_view defines, std::string& error) {
  const auto& shaders = embeddedShaders();
  const auto vertex = shaders.find(vertex_file);
  const auto fragment = shaders.find(fragment_file);
  for (const auto& [name, found] : {std::pair{vertex_file, vertex}, std::pair{fragment_file, fragment}}) {
    if (found == shaders.end()) {
      error = "shader " + std::string(name) +
              " is not embedded in this binary (is it in shaders-gles/ and was CMake re-run?)";
      return std::nullopt;
    }
  }
  if (const FragmentShaderSubstitute& substitute = fragmentShaderSubstitute())
    if (std::optional<std::string> replaced = substitute(fragment_file, defines, fragment->second))
      return fromSources(vertex_file, vertex->second, fragment_file, *replaced, defines, error);
  return fromSources(vertex_file, vertex->second, fragment_file, fragment->second, defines, error);
}

bool FullScreenQuad::init(std::string& error) {
  static constexpr GLfloat kCorners[] = {-1.0f, -1.0f, 1.0f, -1.0f, -1.0f, 1.0f, 1.0f, 1.0f};
  vertices_ = Buffer::create();
  glBindBuffer(GL_ARRAY_BUFFER, vertices_.id());
  glBufferData(GL_ARRAY_BUFFER, sizeof kCorners, kCorners, GL_STATIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  return checkGl("glBufferData(full-screen quad)", error);
}

void FullScreenQuad::draw(GLint position_attribute) const {
  if (position_attribute < 0) return;
  const auto attribute = static_cast<GLuint>(position_attribute);
  glBindBuffer(GL_ARRAY_BUFFER, vertices_.id());
  glEnableVertexAttribArray(attribute);
  glVertexAttribPointer(attribute, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  glDisableVertexAttribArray(attribute);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

}  // namespace probelight::gles
