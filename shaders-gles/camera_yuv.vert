#version 100
// The camera's Y'CbCr planes to the RGB frame texture. The output is a
// texture, stored like an uploaded image (image row 0 at t = 0), so texel t
// of the output reads texel t of the planes: no flip here.
attribute vec2 a_position;
varying vec2 v_texcoord;

void main() {
  v_texcoord = 0.5 * a_position + 0.5;
  gl_Position = vec4(a_position, 0.0, 1.0);
}
