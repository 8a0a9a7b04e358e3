// Each stage against its limit: the same passes (render targets, draws,
// geometry, texture reads per fragment) with a trivial fragment shader that
// only sums as many texture reads as the stage's own shader makes per
// fragment at the shipped defaults. What a stage costs above its limit is
// its arithmetic and control flow; the issue's target is within 2x.
//
// The read counts per shader are the defaults' (counted from the shaders;
// a loop's taps, a manual bilinear lookup's 4 reads):
//   probe_to_cube.frag         1 camera read (the fixed-point normal is arithmetic)
//   cosine_irradiance.frag     prefilter PREFILTER_FACTOR^2; east 4 (2 HALF_TAPS + 1) (a bilinear
//                              cube lookup per tap); north LATLONG_ROWS + 1; resample 4
//   image_quad.frag            1
//   ground_composite.frag      camera 1, fraction 1
//   sphere_object.frag         diffuse 4 and the ladder's rung(s) 4 each
//   shadow_depth.frag          none
//   ground_shadow.frag         16 (the blocker search every fragment makes; the filter's 16 more
//                              only where blockers were found, so the limit is a lower bound)
// A shader not listed keeps its own code (its stage's limit is then its own cost).
#pragma once

#include <map>
#include <optional>
#include <regex>
#include <string>
#include <string_view>

#include "gles/gl_objects.hpp"

namespace probelight::bench {

// `#define NAME value` in the defines, or `fallback`.
inline int defineValue(std::string_view defines, const std::string& name, int fallback) {
  const std::regex pattern("#define " + name + " (-?[0-9]+)");
  std::match_results<std::string_view::const_iterator> match;
  if (std::regex_search(defines.begin(), defines.end(), match, pattern)) return std::stoi(match[1].str());
  return fallback;
}

inline bool defined(std::string_view defines, const std::string& name) {
  return defines.find("#define " + name) != std::string_view::npos;
}

// Texture reads per fragment by sampler, for the shaders the defaults run;
// empty optional for a shader not counted.
inline std::optional<std::map<std::string, int>> readsPerFragment(std::string_view file, std::string_view defines) {
  if (file == "probe_to_cube.frag") return std::map<std::string, int>{{"u_camera", 1}};
  if (file == "image_quad.frag") return std::map<std::string, int>{{"u_image", 1}};
  if (file == "ground_composite.frag") return std::map<std::string, int>{{"u_camera", 1}, {"u_fraction", 1}};
  if (file == "shadow_depth.frag") return std::map<std::string, int>{};
  if (file == "ground_shadow.frag") return std::map<std::string, int>{{"u_shadow_map", 16}};
  if (file == "sphere_object.frag") {
    // Rung kinds: 0 mirror, 1 glossy 0, 2 glossy 1, 3 the diffuse map (already read).
    std::map<std::string, int> reads{{"u_diffuse_map", 4}};
    const char* samplers[] = {"u_reflection_map", "u_glossy0_map", "u_glossy1_map"};
    for (const int kind : {defineValue(defines, "REFLECTION_LOWER_RUNG", 0), defineValue(defines, "REFLECTION_UPPER_RUNG", -1)})
      if (kind >= 0 && kind <= 2) reads[samplers[kind]] += 4;
    return reads;
  }
  if (file == "cosine_irradiance.frag") {
    if (defined(defines, "PREFILTER_PASS")) {
      const int factor = defineValue(defines, "PREFILTER_FACTOR", 4);
      return std::map<std::string, int>{{"u_input", factor * factor}};
    }
    if (defined(defines, "EAST_PASS"))
      return std::map<std::string, int>{{"u_input", 4 * (2 * defineValue(defines, "HALF_TAPS", 16) + 1)}};
    if (defined(defines, "NORTH_PASS"))
      return std::map<std::string, int>{{"u_latlong", defineValue(defines, "LATLONG_ROWS", 32) + 1}};
    if (defined(defines, "RESAMPLE_PASS")) return std::map<std::string, int>{{"u_latlong", 4}};
  }
  return std::nullopt;
}

// The trivial shader: the same samplers, `reads` texture reads at
// coordinates that move with the pixel, summed; nothing else.
inline std::optional<std::string> trivialFragmentShader(std::string_view file, std::string_view defines,
                                                        std::string_view source) {
  const std::optional<std::map<std::string, int>> reads = readsPerFragment(file, defines);
  if (!reads) return std::nullopt;
  std::string declarations, body;
  const std::regex sampler(R"(uniform\s+(sampler2D|samplerCube)\s+(\w+)\s*;)");
  for (std::regex_iterator<std::string_view::const_iterator> it(source.begin(), source.end(), sampler), end; it != end;
       ++it) {
    const std::string type = (*it)[1].str(), name = (*it)[2].str();
    const auto count = reads->find(name);
    if (count == reads->end() || count->second <= 0 || declarations.find(" " + name + ";") != std::string::npos) continue;
    declarations += "uniform " + type + " " + name + ";\n";
    const std::string coordinate =
        type == "samplerCube" ? "normalize(vec3(p + float(k) * 0.0137, 1.0))" : "p + float(k) * 0.0137";
    body += "  for (int k = 0; k < " + std::to_string(count->second) + "; ++k) sum += " +
            (type == "samplerCube" ? "textureCube(" : "texture2D(") + name + ", " + coordinate + ");\n";
  }
  return "#version 100\n" + declarations + "void main() {\n  vec2 p = gl_FragCoord.xy * (1.0 / 64.0);\n" +
         "  vec4 sum = vec4(0.0);\n" + body + "  gl_FragColor = sum * 0.001 + vec4(0.5);\n}\n";
}

// While alive, programs built get their trivial shader: every counted one,
// or only those of `only_file` when it is given.
class TrivialShaderScope {
 public:
  explicit TrivialShaderScope(bool active, std::string only_file = "") : active_(active) {
    if (!active_) return;
    gles::setFragmentShaderSubstitute(
        [only_file](std::string_view file, std::string_view defines, std::string_view source) -> std::optional<std::string> {
          if (!only_file.empty() && file != only_file) return std::nullopt;
          return trivialFragmentShader(file, defines, source);
        });
  }
  ~TrivialShaderScope() {
    if (active_) gles::setFragmentShaderSubstitute(nullptr);
  }
  TrivialShaderScope(const TrivialShaderScope&) = delete;
  TrivialShaderScope& operator=(const TrivialShaderScope&) = delete;

 private:
  bool active_;
};

}  // namespace probelight::bench
