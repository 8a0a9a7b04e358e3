// The GLES cube face table as three axes per face: a face's texel at (s, t)
// looks along center + (2s - 1) s_axis + (2t - 1) t_axis
// (ibl::cubeCoordToDirection). Shared by the passes that draw cube faces and
// by their CPU twins in tests/gles.
#pragma once

#include <array>

#include <glm/glm.hpp>

namespace probelight::passes {

struct FaceBasis {
  glm::vec3 center;
  glm::vec3 s_axis;
  glm::vec3 t_axis;
};

inline constexpr std::array<FaceBasis, 6> kFaceBases{{
    {{1, 0, 0}, {0, 0, -1}, {0, -1, 0}},
    {{-1, 0, 0}, {0, 0, 1}, {0, -1, 0}},
    {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}},
    {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}},
    {{0, 0, 1}, {1, 0, 0}, {0, -1, 0}},
    {{0, 0, -1}, {-1, 0, 0}, {0, -1, 0}},
}};

}  // namespace probelight::passes
