// GLSL ES 1.00 arithmetic at a chosen precision, for the shaders' CPU twins
// (shader_twins.hpp). S is float (what a GPU with fragment highp computes)
// or Mediump16: the IEEE half float that many GLES2 GPUs use for mediump
// (10 stored mantissa bits, largest finite 65504), as GCC's _Float16 rounds
// to it. The rounding is written out (roundToHalf) because clang 14, which
// builds the sanitizer job, has no _Float16 on x86; mediump_test.cpp checks
// it against _Float16 where the compiler has one. A GPU without
// GL_FRAGMENT_PRECISION_HIGH runs all of a fragment shader at mediump
// (gles/gl_objects.cpp's prelude), so every value of the twin is an S.
//
// Each operation is done in float and rounded to S, as a GPU's 16-bit ALU
// rounds every result: a product or a sum of two halves is exact in float,
// so those are correctly rounded; quotients, square roots and the
// transcendentals are rounded twice (float, then half), a difference of at
// most one half-ulp in rare cases, far below what the comparisons resolve.
// Real GPUs' mediump sin/exp/pow are often less accurate than correctly
// rounded ones, so the errors measured here are a lower bound for those.
// Subnormal halves are kept (many GPUs flush them to zero; only values
// below 6.1e-5 differ).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace probelight::glsl {

// x rounded to the nearest IEEE binary16 value (ties to even), as a double:
// subnormals below 2^-14 keep a fixed step of 2^-24, and from 65520 (half
// way to 2^16) on the result overflows to infinity.
inline double roundToHalf(double x) {
  if (!std::isfinite(x) || x == 0.0) return x;
  if (std::fabs(x) >= 65520.0) return std::copysign(HUGE_VAL, x);
  const int exponent = std::max(std::ilogb(x), -14);
  const double ulp = std::ldexp(1.0, exponent - 10);
  return std::nearbyint(x / ulp) * ulp;  // both scalings by powers of two are exact
}

struct Mediump16 {
  float value;  // always a binary16 value
  Mediump16() : value(0.0f) {}
  // Implicit, as GLSL converts a literal or a uniform to the shader's precision.
  Mediump16(double x) : value(static_cast<float>(roundToHalf(x))) {}  // NOLINT(google-explicit-constructor)
  explicit operator float() const { return value; }
  explicit operator double() const { return value; }
};

inline Mediump16 operator+(Mediump16 a, Mediump16 b) { return Mediump16(float(a) + float(b)); }
inline Mediump16 operator-(Mediump16 a, Mediump16 b) { return Mediump16(float(a) - float(b)); }
inline Mediump16 operator*(Mediump16 a, Mediump16 b) { return Mediump16(float(a) * float(b)); }
inline Mediump16 operator/(Mediump16 a, Mediump16 b) { return Mediump16(float(a) / float(b)); }
inline Mediump16 operator-(Mediump16 a) { return Mediump16(-float(a)); }
inline bool operator<(Mediump16 a, Mediump16 b) { return float(a) < float(b); }
inline bool operator>(Mediump16 a, Mediump16 b) { return float(a) > float(b); }
inline bool operator<=(Mediump16 a, Mediump16 b) { return float(a) <= float(b); }
inline bool operator>=(Mediump16 a, Mediump16 b) { return float(a) >= float(b); }
inline Mediump16& operator+=(Mediump16& a, Mediump16 b) { return a = a + b; }
inline Mediump16& operator-=(Mediump16& a, Mediump16 b) { return a = a - b; }
inline Mediump16& operator*=(Mediump16& a, Mediump16 b) { return a = a * b; }
inline Mediump16& operator/=(Mediump16& a, Mediump16 b) { return a = a / b; }

// Scalar functions: computed in float, rounded to S.
template <class S> S fn(float (*f)(float), S x) { return S(f(float(x))); }
template <class S> S sqrt(S x) { return S(std::sqrt(float(x))); }
template <class S> S inversesqrt(S x) { return S(1.0f / std::sqrt(float(x))); }
template <class S> S abs(S x) { return S(std::fabs(float(x))); }
template <class S> S floor(S x) { return S(std::floor(float(x))); }
template <class S> S fract(S x) { return x - floor(x); }
template <class S> S mod(S x, S y) { return x - y * floor(x / y); }
template <class S> S min(S a, S b) { return b < a ? b : a; }
template <class S> S max(S a, S b) { return a < b ? b : a; }
template <class S> S clamp(S x, S lo, S hi) { return min(max(x, lo), hi); }
template <class S> S mix(S a, S b, S t) { return a + (b - a) * t; }
template <class S> S step(S edge, S x) { return x < edge ? S(0.0) : S(1.0); }
template <class S> S pow(S x, S y) { return S(std::pow(float(x), float(y))); }
template <class S> S exp(S x) { return S(std::exp(float(x))); }
template <class S> S exp2(S x) { return S(std::exp2(float(x))); }
template <class S> S log2(S x) { return S(std::log2(float(x))); }
template <class S> S sin(S x) { return S(std::sin(float(x))); }
template <class S> S cos(S x) { return S(std::cos(float(x))); }
template <class S> S atan(S y, S x) { return S(std::atan2(float(y), float(x))); }

template <class S> struct vec2 {
  S x, y;
  vec2() : x(0.0), y(0.0) {}
  explicit vec2(S s) : x(s), y(s) {}
  vec2(S x_, S y_) : x(x_), y(y_) {}
  S& operator[](int i) { return i == 0 ? x : y; }
};
template <class S> struct vec3 {
  S x, y, z;
  vec3() : x(0.0), y(0.0), z(0.0) {}
  explicit vec3(S s) : x(s), y(s), z(s) {}
  vec3(S x_, S y_, S z_) : x(x_), y(y_), z(z_) {}
  vec2<S> xy() const { return {x, y}; }
  S& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  S operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};
template <class S> struct vec4 {
  S x, y, z, w;
  vec4() : x(0.0), y(0.0), z(0.0), w(0.0) {}
  explicit vec4(S s) : x(s), y(s), z(s), w(s) {}
  vec4(S x_, S y_, S z_, S w_) : x(x_), y(y_), z(z_), w(w_) {}
  vec4(vec3<S> v, S w_) : x(v.x), y(v.y), z(v.z), w(w_) {}
  vec3<S> rgb() const { return {x, y, z}; }
  vec2<S> xy() const { return {x, y}; }
  S& operator[](int i) { return i == 0 ? x : (i == 1 ? y : (i == 2 ? z : w)); }
  S operator[](int i) const { return i == 0 ? x : (i == 1 ? y : (i == 2 ? z : w)); }
};

// Component-wise operators and functions, written once for the three sizes.
#define PL_GLSL_COMPONENTWISE(V, N)                                                                         \
  template <class S> V<S> operator+(V<S> a, V<S> b) { V<S> r; for (int i = 0; i < N; ++i) r[i] = a[i] + b[i]; return r; } \
  template <class S> V<S> operator-(V<S> a, V<S> b) { V<S> r; for (int i = 0; i < N; ++i) r[i] = a[i] - b[i]; return r; } \
  template <class S> V<S> operator*(V<S> a, V<S> b) { V<S> r; for (int i = 0; i < N; ++i) r[i] = a[i] * b[i]; return r; } \
  template <class S> V<S> operator/(V<S> a, V<S> b) { V<S> r; for (int i = 0; i < N; ++i) r[i] = a[i] / b[i]; return r; } \
  template <class S> V<S> operator*(S s, V<S> a) { V<S> r; for (int i = 0; i < N; ++i) r[i] = s * a[i]; return r; }      \
  template <class S> V<S> operator*(V<S> a, S s) { return s * a; }                                                     \
  template <class S> V<S> operator/(V<S> a, S s) { V<S> r; for (int i = 0; i < N; ++i) r[i] = a[i] / s; return r; }      \
  template <class S> V<S> operator+(V<S> a, S s) { V<S> r; for (int i = 0; i < N; ++i) r[i] = a[i] + s; return r; }      \
  template <class S> V<S> operator-(V<S> a, S s) { V<S> r; for (int i = 0; i < N; ++i) r[i] = a[i] - s; return r; }      \
  template <class S> V<S> operator-(V<S> a) { V<S> r; for (int i = 0; i < N; ++i) r[i] = -a[i]; return r; }              \
  template <class S> V<S>& operator+=(V<S>& a, V<S> b) { return a = a + b; }                                           \
  template <class S> V<S>& operator*=(V<S>& a, S s) { return a = a * s; }                                              \
  template <class S> V<S>& operator/=(V<S>& a, S s) { return a = a / s; }                                              \
  template <class S> S dot(V<S> a, V<S> b) { S r = a[0] * b[0]; for (int i = 1; i < N; ++i) r += a[i] * b[i]; return r; } \
  template <class S> V<S> map(V<S> a, S (*f)(S)) { V<S> r; for (int i = 0; i < N; ++i) r[i] = f(a[i]); return r; }     \
  template <class S> V<S> sqrt(V<S> a) { return map(a, &glsl::sqrt<S>); }                                               \
  template <class S> V<S> abs(V<S> a) { return map(a, &glsl::abs<S>); }                                                 \
  template <class S> V<S> floor(V<S> a) { return map(a, &glsl::floor<S>); }                                             \
  template <class S> V<S> clamp(V<S> a, S lo, S hi) { V<S> r; for (int i = 0; i < N; ++i) r[i] = clamp(a[i], lo, hi); return r; } \
  template <class S> V<S> clamp(V<S> a, V<S> lo, V<S> hi) { V<S> r; for (int i = 0; i < N; ++i) r[i] = clamp(a[i], lo[i], hi[i]); return r; } \
  template <class S> V<S> max(V<S> a, V<S> b) { V<S> r; for (int i = 0; i < N; ++i) r[i] = max(a[i], b[i]); return r; } \
  template <class S> V<S> min(V<S> a, V<S> b) { V<S> r; for (int i = 0; i < N; ++i) r[i] = min(a[i], b[i]); return r; } \
  template <class S> V<S> mix(V<S> a, V<S> b, S t) { V<S> r; for (int i = 0; i < N; ++i) r[i] = mix(a[i], b[i], t); return r; } \
  template <class S> V<S> mix(V<S> a, V<S> b, V<S> t) { V<S> r; for (int i = 0; i < N; ++i) r[i] = mix(a[i], b[i], t[i]); return r; } \
  template <class S> V<S> step(V<S> edge, V<S> x) { V<S> r; for (int i = 0; i < N; ++i) r[i] = step(edge[i], x[i]); return r; } \
  template <class S> V<S> pow(V<S> a, V<S> e) { V<S> r; for (int i = 0; i < N; ++i) r[i] = pow(a[i], e[i]); return r; } \
  template <class S> S length(V<S> a) { return sqrt(dot(a, a)); }                                                      \
  template <class S> V<S> normalize(V<S> a) { return a * inversesqrt(dot(a, a)); }

PL_GLSL_COMPONENTWISE(vec2, 2)
PL_GLSL_COMPONENTWISE(vec3, 3)
PL_GLSL_COMPONENTWISE(vec4, 4)
#undef PL_GLSL_COMPONENTWISE

template <class S> vec3<S> cross(vec3<S> a, vec3<S> b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class S> vec3<S> reflect(vec3<S> i, vec3<S> n) { return i - S(2.0) * dot(n, i) * n; }

// A column-major mat3 / mat4 times a vector, as GLSL's m * v.
template <class S> vec3<S> mul(const vec3<S> (&columns)[3], vec3<S> v) {
  return columns[0] * v.x + columns[1] * v.y + columns[2] * v.z;
}
template <class S> vec4<S> mul(const vec4<S> (&columns)[4], vec4<S> v) {
  return columns[0] * v.x + columns[1] * v.y + columns[2] * v.z + columns[3] * v.w;
}

template <class S> vec3<S> toVec3(double x, double y, double z) { return {S(x), S(y), S(z)}; }

}  // namespace probelight::glsl
