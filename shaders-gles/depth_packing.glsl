// Depth in [0, 1] in the red and green bytes of an RGBA8 texel, for GPUs
// without OES_depth_texture: 16 bits where the fragment shader has highp;
// with 16-bit mediump the low byte is rounding noise and depth keeps ~11
// bits (1/2048 of the shadow map's depth range, a few hundredths of a
// millimetre for a 7 cm object), which the comparison bias covers.
//
// Both directions work in depth * 65535 / 256 (at most 255.996), never in
// depth * 65535 itself: a 16-bit float holds only up to 65504, so packing
// depth 1.0 gave inf (and its low byte NaN) and unpacking it gave inf
// (tests/gles/mediump_test.cpp).
vec4 packDepth(float depth01) {
  float high_and_fraction = clamp(depth01, 0.0, 1.0) * (65535.0 / 256.0);
  // Both bytes saturate rather than carry: at 16 bits the product next to
  // 1 rounds up to 256, and a low byte rounding up to 256 would carry there
  // too. Saturating costs at most one 16-bit step of depth (1.5e-5).
  float high = min(floor(high_and_fraction), 255.0);
  float low = min(floor((high_and_fraction - high) * 256.0 + 0.5), 255.0);
  return vec4(high / 255.0, low / 255.0, 0.0, 1.0);
}

float unpackDepth(vec4 stored) {
  return (floor(stored.r * 255.0 + 0.5) + floor(stored.g * 255.0 + 0.5) / 256.0) * (256.0 / 65535.0);
}
