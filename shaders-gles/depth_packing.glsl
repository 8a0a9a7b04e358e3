// Depth in [0, 1] in the red and green bytes of an RGBA8 texel, for GPUs
// without OES_depth_texture: 16 bits where the fragment shader has highp;
// with 16-bit mediump the low byte is rounding noise and depth keeps ~11
// bits (1/2048 of the shadow map's depth range, a few hundredths of a
// millimetre for a 7 cm object), which the comparison bias covers.
vec4 packDepth(float depth01) {
  float scaled = floor(clamp(depth01, 0.0, 1.0) * 65535.0 + 0.5);
  float high = floor(scaled / 256.0);
  return vec4(high / 255.0, (scaled - high * 256.0) / 255.0, 0.0, 1.0);
}

float unpackDepth(vec4 stored) {
  return (floor(stored.r * 255.0 + 0.5) * 256.0 + floor(stored.g * 255.0 + 0.5)) / 65535.0;
}
