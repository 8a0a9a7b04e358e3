// IEC 61966-2-1 sRGB curve, as ibl/color_transfer.cpp (inputs clamped to [0, 1]).
vec3 srgbToLinear(vec3 encoded) {
  vec3 c = clamp(encoded, 0.0, 1.0);
  vec3 low = c / 12.92;
  vec3 high = pow((c + 0.055) / 1.055, vec3(2.4));
  return mix(high, low, step(c, vec3(0.04045)));
}

vec3 linearToSrgb(vec3 linear) {
  vec3 l = clamp(linear, 0.0, 1.0);
  vec3 low = 12.92 * l;
  vec3 high = 1.055 * pow(l, vec3(1.0 / 2.4)) - 0.055;
  return mix(high, low, step(l, vec3(0.0031308)));
}
