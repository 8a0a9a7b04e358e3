#version 100
// Virtual sphere: each vertex is projected with the calibrated pinhole and
// the 5-term distortion (camera_projection.glsl), so the object lands where
// ibl::projectToPixel puts it. Pixel (u, v) of OpenCV's convention has its
// centre at window (u + 0.5, v + 0.5); image row 0 is at NDC y = +1.
#include "camera_projection.glsl"

attribute vec3 a_unit;  // unit sphere point = outward normal in W

uniform vec3 u_center_w;
uniform float u_radius_m;
uniform mat3 u_rotation_cam_from_world;
uniform vec3 u_translation_cam_from_world;
uniform vec3 u_eye_w;
uniform vec4 u_distortion;
uniform float u_distortion_k3;
uniform vec2 u_focal_px;
uniform vec2 u_principal_px;
uniform vec2 u_image_size_px;
uniform vec2 u_depth_range_m;  // near, far

varying vec3 v_normal_w;
varying vec3 v_to_eye_w;

void main() {
  vec3 position_w = u_center_w + u_radius_m * a_unit;
  vec3 position_cam = u_rotation_cam_from_world * position_w + u_translation_cam_from_world;
  float z = position_cam.z;
  vec2 distorted = distortNormalized(position_cam.xy / z, u_distortion, u_distortion_k3);
  vec2 pixel = u_focal_px * distorted + u_principal_px;
  vec2 ndc = vec2(2.0 * (pixel.x + 0.5) / u_image_size_px.x - 1.0, 1.0 - 2.0 * (pixel.y + 0.5) / u_image_size_px.y);
  float depth_ndc = 2.0 * (z - u_depth_range_m.x) / (u_depth_range_m.y - u_depth_range_m.x) - 1.0;
  // w = z keeps varyings perspective-correct; the divide gives back ndc.
  gl_Position = vec4(ndc * z, depth_ndc * z, z);
  v_normal_w = a_unit;
  // Exactly linear in the position, so interpolating it is exact on the facet.
  v_to_eye_w = u_eye_w - position_w;
}
