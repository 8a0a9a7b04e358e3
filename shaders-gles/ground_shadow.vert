#version 100
// The square of ground the shadows can reach, rasterised into its own
// texture: texel (i, j) is ground point centre + half_size (2 (i, j) + 1) / N - 1.
// Drawn one light at a time over the part its shadow can reach.
attribute vec2 a_position;  // the texture's NDC, [-1, 1]^2 over the square
uniform vec2 u_region_centre_w;
uniform float u_region_half_size_m;
varying vec2 v_ground_w;

void main() {
  v_ground_w = u_region_centre_w + u_region_half_size_m * a_position;
  gl_Position = vec4(a_position, 0.0, 1.0);
}
