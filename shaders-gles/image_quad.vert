#version 100
// Full-screen image quad under the screen convention: image row 0 (t = 0)
// at NDC y = +1, the top of the picture.
attribute vec2 a_position;
varying vec2 v_texcoord;

void main() {
  v_texcoord = vec2(0.5 * a_position.x + 0.5, 0.5 - 0.5 * a_position.y);
  gl_Position = vec4(a_position, 0.0, 1.0);
}
