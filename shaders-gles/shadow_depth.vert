#version 100
// A shadow-casting object seen from one directional light (orthographic).
attribute vec3 a_position_w;
uniform mat4 u_light_clip_from_world;
varying float v_depth01;

void main() {
  gl_Position = u_light_clip_from_world * vec4(a_position_w, 1.0);
  v_depth01 = 0.5 * gl_Position.z + 0.5;
}
