#version 100
// Stage 4: ibl::shadeSurface in linear light, then sRGB-encoded (clamped).
#include "color_transfer.glsl"
#include "cube_storage.glsl"

varying vec3 v_normal_w;
varying vec3 v_to_eye_w;

uniform samplerCube u_diffuse_map;
uniform float u_diffuse_face_size;
uniform float u_diffuse_scale;
uniform samplerCube u_reflection_map;
uniform float u_reflection_face_size;
uniform float u_reflection_scale;

uniform vec3 u_albedo;
uniform float u_material_ambient;
uniform float u_k_diffuse;
uniform float u_k_specular;
uniform float u_shininess;
uniform float u_k_reflect;
uniform vec3 u_ambient_rgb;
uniform vec3 u_highlight_direction_w;
uniform vec3 u_highlight_rgb;

void main() {
  vec3 n = normalize(v_normal_w);
  vec3 to_eye = normalize(v_to_eye_w);
  vec3 half_vector = normalize(u_highlight_direction_w + to_eye);
  float n_dot_h = max(dot(n, half_vector), 0.0);
  float highlight = n_dot_h > 0.0 ? pow(n_dot_h, u_shininess) : 0.0;
  vec3 mirror = reflect(-to_eye, n);
  vec3 diffuse = sampleCubeBilinear(u_diffuse_map, n, u_diffuse_face_size, u_diffuse_scale).rgb;
  vec3 reflection = sampleCubeBilinear(u_reflection_map, mirror, u_reflection_face_size, u_reflection_scale).rgb;
  vec3 color = u_ambient_rgb * u_material_ambient + u_k_diffuse * diffuse * u_albedo +
               u_k_specular * u_highlight_rgb * highlight + u_k_reflect * reflection;
  gl_FragColor = vec4(linearToSrgb(color), 1.0);
}
