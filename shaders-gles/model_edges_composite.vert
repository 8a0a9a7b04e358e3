#version 100
// The model's anti-aliasing layer (passes/edge_antialiasing) over the frame:
// a full-screen quad. The layer was drawn with the same NDC as the frame, so
// its texture coordinate is NDC * 0.5 + 0.5 with no flip (the camera image's
// quad flips because that image is uploaded top row first; this one is not).
//
// GRID is the layer's factor k (1: a resolved multisampled layer of the
// frame's size). The resolve reads each 2 x 2 block of sub-samples with one
// bilinear fetch at the block's centre, where the four weights are 1/4: one
// fetch for k = 2, four for k = 4 (at the pixel's centre -+ one layer texel).
// The fetch places are made here, in highp, and reach the fragment shader as
// varyings it passes straight to texture2D: a mediump fragment shader adding
// offsets itself would miss by up to 0.6 of a texel in a 2560-texel layer.
attribute vec2 a_position;
uniform vec2 u_layer_texel;  // 1 / the layer's size in texels
#if GRID == 4
varying vec4 v_taps_low;   // xy: (-1, -1) texel from the centre, zw: (+1, -1)
varying vec4 v_taps_high;  // xy: (-1, +1), zw: (+1, +1)
#else
varying vec2 v_tap;        // the pixel's centre
#endif

void main() {
  vec2 uv = 0.5 * a_position + 0.5;
#if GRID == 4
  v_taps_low = vec4(uv - u_layer_texel, uv + vec2(u_layer_texel.x, -u_layer_texel.y));
  v_taps_high = vec4(uv + vec2(-u_layer_texel.x, u_layer_texel.y), uv + u_layer_texel);
#else
  v_tap = uv;
#endif
  gl_Position = vec4(a_position, 0.0, 1.0);
}
