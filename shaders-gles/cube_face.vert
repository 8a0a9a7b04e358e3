#version 100
// Full-screen quad over one cube face bound as the colour attachment. GL
// writes window row 0 to texture row 0 (t near 0), so st is NDC mapped to
// [0, 1] without a flip; at fragment (x + 0.5, y + 0.5) st is the texel centre.
attribute vec2 a_position;
varying vec2 v_face_st;

void main() {
  v_face_st = 0.5 * a_position + 0.5;
  gl_Position = vec4(a_position, 0.0, 1.0);
}
