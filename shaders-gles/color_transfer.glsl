// IEC 61966-2-1 sRGB curve, as ibl/color_transfer.cpp (inputs clamped to [0, 1]).
//
// The decode's upper segment x^2.4, x = (c + 0.055) / 1.055, is written as
// x^2 sqrt(x) x^-0.1 with x^-0.1 a degree-5 polynomial in sqrt(x) - 0.6504
// (interpolated at the Chebyshev nodes of the segment, sqrt(x) in
// [0.2990, 1]), instead of pow(): pow is exp2(2.4 log2 x), several times the
// arithmetic, and this runs on every camera and 8-bit cube read. Its largest
// relative error on the segment is 9.5e-5 at 32-bit floats: under 1.1% of one
// code step of the 8-bit values it decodes (a step is 0.9% to 10% of the
// value), and under a 16-bit mediump float's own resolution (4.9e-4).
vec3 srgbToLinear(vec3 encoded) {
  vec3 c = clamp(encoded, 0.0, 1.0);
  vec3 low = c * (1.0 / 12.92);
  vec3 x = c * (1.0 / 1.055) + 0.055 / 1.055;
  vec3 s = sqrt(x);
  vec3 u = s - 0.650394426;
  vec3 x_pow_minus_tenth =
      ((((-0.803481682 * u + 0.610555156) * u - 0.336195787) * u + 0.300160814) * u - 0.335218796) * u + 1.08990671;
  vec3 high = x * x * s * x_pow_minus_tenth;
  return mix(high, low, step(c, vec3(0.04045)));
}

vec3 linearToSrgb(vec3 linear) {
  vec3 l = clamp(linear, 0.0, 1.0);
  vec3 low = 12.92 * l;
  vec3 high = 1.055 * pow(l, vec3(1.0 / 2.4)) - 0.055;
  return mix(high, low, step(l, vec3(0.0031308)));
}
