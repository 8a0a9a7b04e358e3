// Extension strings (GL_EXTENSIONS, EGL_EXTENSIONS) are space-separated
// names; one name can be a prefix of another (GL_OES_texture_half_float and
// GL_OES_texture_half_float_linear), so a plain substring search is wrong.
#pragma once

#include <cstring>

namespace probelight::gles {

inline bool hasExtension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const size_t length = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += length) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[length] == ' ' || p[length] == '\0';
    if (starts && ends) return true;
  }
  return false;
}

}  // namespace probelight::gles
