// Whether every component of a glm vector is finite (no NaN, no infinity).
#pragma once

#include <cmath>

#include <glm/glm.hpp>

namespace probelight {

template <glm::length_t N, typename T, glm::qualifier Q>
bool allFinite(const glm::vec<N, T, Q>& v) {
  for (glm::length_t i = 0; i < N; ++i) {
    if (!std::isfinite(v[i])) return false;
  }
  return true;
}

}  // namespace probelight
