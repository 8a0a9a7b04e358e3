#version 100
// The square of ground the shadows can reach, rasterised into its own
// texture: texel (i, j) is ground point centre + half_size (2 (i, j) + 1) / N - 1.
// Drawn one light at a time over the part its shadow can reach.
attribute vec2 a_position;  // the texture's NDC, [-1, 1]^2 over the square
uniform vec2 u_region_centre_w;
uniform float u_region_half_size_m;
uniform mat4 u_light_clip_from_world;
// The ground point in the light's clip space, made here at highp: it is
// affine in the quad's position, so the rasteriser interpolates it exactly.
// In a 16-bit fragment shader the product's terms (a matrix entry of ~25
// times decimetres) cancel to a depth of O(1): inside the light's map the
// clip depth lost 1.0e-3 there, half the comparison's bias; made here, only
// the varying's own rounding is left (4.9e-4), and the fragment shader
// does 16 multiply-adds less (tests/gles/mediump_test.cpp).
varying vec3 v_light_clip;

void main() {
  vec2 ground_w = u_region_centre_w + u_region_half_size_m * a_position;
  v_light_clip = (u_light_clip_from_world * vec4(ground_w, 0.0, 1.0)).xyz;
  gl_Position = vec4(a_position, 0.0, 1.0);
}
