// The GLSL ES files of shaders-gles/, compiled into the binary by
// cmake/embed_shaders.cmake and keyed by file name ("probe_to_cube.frag").
#pragma once

#include <functional>
#include <map>
#include <string>

namespace probelight::gles {

const std::map<std::string, std::string, std::less<>>& embeddedShaders();

}  // namespace probelight::gles
