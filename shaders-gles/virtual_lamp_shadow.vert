#version 100
// The object's shadow from the virtual lamp (passes/virtual_lamp_light):
// its triangles flattened onto the ground from the lamp (the planar
// projection ibl::groundShadowProjection), placed in the pool's square.
// Vertex shaders are highp in GLSL ES 1.00.
attribute vec3 a_position_w;
uniform mat4 u_clip_from_world;

void main() {
  gl_Position = u_clip_from_world * vec4(a_position_w, 1.0);
}
