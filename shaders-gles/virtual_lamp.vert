#version 100
// The virtual lamp's pass over the whole frame (passes/virtual_lamp_light):
// a grid over the image whose vertices carry the camera's undistorted ray
// through their pixel (computed once on the CPU, through the lens model),
// turned into W here. Between vertices the ray is interpolated linearly in
// the image, which is exact for a pinhole; the lens bends it by far less
// than a pixel across a cell. Vertex shaders are highp in GLSL ES 1.00.
attribute vec2 a_ndc;
attribute vec3 a_ray_cam;
uniform mat3 u_world_from_cam;
varying vec3 v_ray_w;

void main() {
  v_ray_w = u_world_from_cam * a_ray_cam;
  gl_Position = vec4(a_ndc, 0.0, 1.0);
}
