#version 100
// The resolved model layer, premultiplied by coverage (passes/
// edge_antialiasing.hpp): the mean of the pixel's sub-samples, each the
// model's colour where the model covers it and transparent black elsewhere.
// Blended with GL_ONE, GL_ONE_MINUS_SRC_ALPHA: out = layer + (1 - a) video.
//
// GRID 2: one bilinear fetch at the pixel's centre, the corner the pixel's
// 2 x 2 sub-samples share (weights 1/4 each). GRID 4: four such fetches,
// each weighted 1/4 (a power of two: the scaling is exact in any precision;
// the sum of four values under 1 keeps mediump's 2^-11 to under half an
// 8-bit step). GRID 1: the texel itself (NEAREST), already resolved by the GPU.
//
// MATCH_SENSOR_NOISE (the grids): the frame's noise is added here, after the
// resolve, not by the model's shader: the mean of GRID^2 sub-samples would
// divide its sigma by GRID. The layer holds the model's colour c times its
// coverage a, so the noise enters times a as well: a (c + n) + (1 - a) video.
#include "color_transfer.glsl"
#include "camera_transfer.glsl"
#include "camera_response.glsl"
#if GRID == 4
varying vec4 v_taps_low;
varying vec4 v_taps_high;
#else
varying vec2 v_tap;
#endif
uniform sampler2D u_layer;

void main() {
#if GRID == 4
  vec4 layer = 0.25 * (texture2D(u_layer, v_taps_low.xy) + texture2D(u_layer, v_taps_low.zw)) +
               0.25 * (texture2D(u_layer, v_taps_high.xy) + texture2D(u_layer, v_taps_high.zw));
#else
  vec4 layer = texture2D(u_layer, v_tap);
#endif
#ifdef MATCH_SENSOR_NOISE
  layer.rgb += layer.a * sensorNoise(layer.rgb / max(layer.a, 1.0 / 255.0));
#endif
  gl_FragColor = layer;
}
