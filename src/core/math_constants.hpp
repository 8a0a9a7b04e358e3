// Constants that many files need, defined once (each file defining its own
// in an anonymous namespace also breaks a unity build, where several files
// share one translation unit).
#pragma once

#include <numbers>

namespace probelight {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kRadPerDeg = kPi / 180.0;

constexpr double degToRad(double deg) { return deg * kRadPerDeg; }

}  // namespace probelight
