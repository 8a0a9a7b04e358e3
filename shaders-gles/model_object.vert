#version 100
// A glTF model's primitive (passes/model_renderer): vertices already placed
// in W on the CPU, projected with the calibrated pinhole and the 5-term
// distortion as sphere_object.vert. Attributes the primitive lacks are not
// declared (HAS_TANGENT, HAS_UV0, HAS_UV1, HAS_COLOR).
#include "camera_projection.glsl"

attribute vec3 a_position_w;
attribute vec3 a_normal_w;
#ifdef HAS_TANGENT
attribute vec4 a_tangent_w;  // xyz, w = handedness
varying vec4 v_tangent_w;
#endif
#ifdef HAS_UV0
attribute vec2 a_uv0;
varying vec2 v_uv0;
#endif
#ifdef HAS_UV1
attribute vec2 a_uv1;
varying vec2 v_uv1;
#endif
#ifdef HAS_COLOR
attribute vec4 a_color;
varying vec4 v_color;
#endif

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
#if defined(SELF_SHADOW_LIGHTS) || defined(NEAR_FLOOR)
varying vec3 v_position_w;
#endif

void main() {
  vec3 position_cam = u_rotation_cam_from_world * a_position_w + u_translation_cam_from_world;
  float z = position_cam.z;
  vec2 distorted = distortNormalized(position_cam.xy / z, u_distortion, u_distortion_k3);
  vec2 pixel = u_focal_px * distorted + u_principal_px;
  vec2 ndc = vec2(2.0 * (pixel.x + 0.5) / u_image_size_px.x - 1.0, 1.0 - 2.0 * (pixel.y + 0.5) / u_image_size_px.y);
  float depth_ndc = 2.0 * (z - u_depth_range_m.x) / (u_depth_range_m.y - u_depth_range_m.x) - 1.0;
  gl_Position = vec4(ndc * z, depth_ndc * z, z);
  v_normal_w = a_normal_w;
  v_to_eye_w = u_eye_w - a_position_w;
#if defined(SELF_SHADOW_LIGHTS) || defined(NEAR_FLOOR)
  v_position_w = a_position_w;
#endif
#ifdef HAS_TANGENT
  v_tangent_w = a_tangent_w;
#endif
#ifdef HAS_UV0
  v_uv0 = a_uv0;
#endif
#ifdef HAS_UV1
  v_uv1 = a_uv1;
#endif
#ifdef HAS_COLOR
  v_color = a_color;
#endif
}
