#version 100
// The shadowed square of ground, drawn over the camera image where the
// camera sees it: each vertex projected with the calibrated pinhole and the
// 5-term distortion, as sphere_object.vert.
#include "camera_projection.glsl"

attribute vec2 a_region_uv;  // [0, 1]^2 over the square

uniform vec2 u_region_centre_w;
uniform float u_region_half_size_m;
uniform mat3 u_rotation_cam_from_world;
uniform vec3 u_translation_cam_from_world;
uniform vec4 u_distortion;
uniform float u_distortion_k3;
uniform vec2 u_focal_px;
uniform vec2 u_principal_px;
uniform vec2 u_image_size_px;

varying vec2 v_region_uv;

void main() {
  vec3 position_w = vec3(u_region_centre_w + u_region_half_size_m * (2.0 * a_region_uv - 1.0), 0.0);
  vec3 position_cam = u_rotation_cam_from_world * position_w + u_translation_cam_from_world;
  // Points behind the camera are pushed off screen; the ground square is
  // drawn only when the camera sees it from above, in front.
  float z = max(position_cam.z, 1e-4);
  vec2 distorted = distortNormalized(position_cam.xy / z, u_distortion, u_distortion_k3);
  vec2 pixel = u_focal_px * distorted + u_principal_px;
  vec2 ndc = vec2(2.0 * (pixel.x + 0.5) / u_image_size_px.x - 1.0, 1.0 - 2.0 * (pixel.y + 0.5) / u_image_size_px.y);
  gl_Position = vec4(ndc * z, 0.0, z);
  v_region_uv = a_region_uv;
}
