#version 100
// A glTF metallic-roughness surface lit from the maps, as
// ibl::shadeMetallicRoughness (src/ibl/metallic_roughness.hpp):
//   c = occlusion [c_diff (1 - E_s) D(n) + E_s R(r, roughness)] + emissive,
// then through the camera's response (camera_response.glsl: its transfer,
// and its noise when matched and the model is not drawn into a supersampled
// layer, whose resolve adds the noise instead: model_edges_composite.frag).
//
// Built per material (passes/model_renderer.cpp): each texture the material
// has defines <SLOT>_TEXTURE and <SLOT>_UV (the varying of its TEXCOORD
// set, v_uv0 or v_uv1: GLSL ES 1.00 has no token pasting), and the
// specular rungs its roughness can reach are RUNG_FIRST..RUNG_LAST of the
// ladder 0 mirror, 1..GLOSSY_LEVELS glossy, GLOSSY_LEVELS + 1 diffuse. Only
// those rungs' cube maps are declared and read: on GPUs that run every side
// of a branch (llvmpipe) an unread rung would still cost four cube reads.
//
// Precision: everything here is a colour, a unit vector or a roughness;
// 16-bit mediump keeps them to 2^-11, under half an 8-bit step. Nothing
// divides by a roughness: the ladder position divides only by differences
// of the rung alphas, constants at least 0.04 apart.
#include "color_transfer.glsl"
#include "cube_storage.glsl"
#include "camera_transfer.glsl"
#include "camera_response.glsl"
#ifdef NEAR_FLOOR_CAMERA
#include "camera_projection.glsl"
#endif
#include "depth_packing.glsl"

#ifndef GLOSSY_LEVELS
#define GLOSSY_LEVELS 0
#endif
#define DIFFUSE_RUNG (GLOSSY_LEVELS + 1)
#ifndef RUNG_FIRST
#define RUNG_FIRST 0
#endif
#ifndef RUNG_LAST
#define RUNG_LAST RUNG_FIRST
#endif

varying vec3 v_normal_w;
varying vec3 v_to_eye_w;
#ifdef HAS_TANGENT
varying vec4 v_tangent_w;
#endif
#ifdef HAS_UV0
varying vec2 v_uv0;
#endif
#ifdef HAS_UV1
varying vec2 v_uv1;
#endif
#ifdef HAS_COLOR
varying vec4 v_color;
#endif

uniform samplerCube u_diffuse_map;
uniform float u_diffuse_face_size;
uniform float u_diffuse_scale;
#if RUNG_FIRST == 0
uniform samplerCube u_reflection_map;
uniform float u_reflection_face_size;
uniform float u_reflection_scale;
#endif
#if GLOSSY_LEVELS >= 1 && RUNG_FIRST <= 1 && RUNG_LAST >= 1
#define READS_GLOSSY0
uniform samplerCube u_glossy0_map;
uniform float u_glossy0_face_size;
uniform float u_glossy0_scale;
#endif
#if GLOSSY_LEVELS >= 2 && RUNG_FIRST <= 2 && RUNG_LAST >= 2
#define READS_GLOSSY1
uniform samplerCube u_glossy1_map;
uniform float u_glossy1_face_size;
uniform float u_glossy1_scale;
#endif
// The ladder's rung alphas (ibl::specularRungAlphas), rungs 0..DIFFUSE_RUNG.
uniform float u_rung_alpha[4];
// The split-sum environment BRDF (ibl::EnvironmentBrdfTable): luminance
// the scale of F0, alpha the bias.
uniform sampler2D u_brdf_table;
uniform float u_brdf_table_size;

uniform vec4 u_base_color_factor;
uniform float u_metallic_factor;
uniform float u_roughness_factor;
uniform vec3 u_emissive_factor;
uniform float u_normal_scale;
uniform float u_occlusion_strength;
uniform float u_alpha_cutoff;
// ibl::SceneLighting's clipped lights, added to the diffuse light.
uniform vec3 u_clipped_direction_w[4];
uniform vec3 u_clipped_diffuse_rgb[4];
uniform vec3 u_lamp_direction_w;  // a virtual lamp, seen from the object's middle (ibl::SceneLighting)
uniform vec3 u_lamp_diffuse_rgb;

#ifdef BASE_COLOR_TEXTURE
uniform sampler2D u_base_color_texture;
uniform mat3 u_base_color_uv_transform;
#endif
#ifdef METALLIC_ROUGHNESS_TEXTURE
uniform sampler2D u_metallic_roughness_texture;
uniform mat3 u_metallic_roughness_uv_transform;
#endif
#ifdef NORMAL_TEXTURE
uniform sampler2D u_normal_texture;
uniform mat3 u_normal_uv_transform;
#endif
#ifdef OCCLUSION_TEXTURE
uniform sampler2D u_occlusion_texture;
uniform mat3 u_occlusion_uv_transform;
#endif
#ifdef EMISSIVE_TEXTURE
uniform sampler2D u_emissive_texture;
uniform mat3 u_emissive_uv_transform;
#endif

#if defined(SELF_SHADOW_LIGHTS) || defined(NEAR_FLOOR)
varying vec3 v_position_w;
#endif

#ifdef NEAR_FLOOR
// The floor beside the model (ibl/near_floor.hpp): a specular direction
// that goes down reads the maps where the ball's centre sees the ground
// point it meets, darkened by the ground shadow's fraction there
// (NEAR_FLOOR_SHADOW: passes/ground_shadow's texture over the square
// centred at u_ground_region.xy, u_ground_region.z = 1 / its side).
// Precision: the point is within metres of the origin and the distance
// along the ray is held to NEAR_FLOOR_MAX_DISTANCE_M, so every term stays
// well inside a 16-bit float's range; the direction is a unit vector.
uniform vec3 u_ball_centre_w;
uniform float u_ball_radius_m;
uniform vec3 u_ball_to_eye_w;
#ifdef NEAR_FLOOR_SHADOW
uniform sampler2D u_ground_fraction;
uniform vec3 u_ground_region;
#endif
#ifdef NEAR_FLOOR_CAMERA
// The frame the camera took, and where a ground point falls in it
// (ibl::cameraFloorWeight hands over to the maps near its edge). Names of
// their own: a uniform the vertex shader also declares would have to agree
// in precision.
uniform sampler2D u_floor_camera;
uniform vec3 u_floor_camera_to_maps;  // the frame's units into the maps' (exposure and white balance)
uniform mat3 u_floor_rotation_cam_from_world;
uniform vec3 u_floor_translation_cam_from_world;
uniform vec4 u_floor_distortion;
uniform float u_floor_distortion_k3;
uniform vec2 u_floor_focal_px;
uniform vec2 u_floor_principal_px;
uniform vec2 u_floor_image_size_px;
uniform float u_floor_reach2;  // ibl::cameraFloorReach2

vec4 cameraFloor(vec2 ground) {
  vec3 p = u_floor_rotation_cam_from_world * vec3(ground, 0.0) + u_floor_translation_cam_from_world;
  if (p.z <= 1e-3) return vec4(0.0);
  vec2 normalized = p.xy / p.z;
  // Past the lens's calibrated range (and before a 16-bit float overflows).
  if (dot(normalized, normalized) > u_floor_reach2) return vec4(0.0);
  vec2 pixel = u_floor_focal_px * distortNormalized(normalized, u_floor_distortion, u_floor_distortion_k3) +
               u_floor_principal_px;
  vec2 inside = min(pixel + 0.5, u_floor_image_size_px - 0.5 - pixel);
  float weight = clamp(min(inside.x, inside.y) / CAMERA_FLOOR_MARGIN_PX, 0.0, 1.0);
  // The frame is upright in its texture, t = 0 at the top row.
  vec3 seen = decodeCamera(texture2D(u_floor_camera, (pixel + 0.5) / u_floor_image_size_px).rgb) * u_floor_camera_to_maps;
  return vec4(seen, weight);
}
#endif

vec3 nearFloorDirection(vec3 position, vec3 direction, out vec3 fraction, out vec4 camera_floor) {
  fraction = vec3(1.0);
  camera_floor = vec4(0.0);
  if (direction.z >= 0.0) return direction;
  float distance_m = min(max(position.z, 0.0) / -direction.z, NEAR_FLOOR_MAX_DISTANCE_M);
  vec2 ground = position.xy + distance_m * direction.xy;
#ifdef NEAR_FLOOR_SHADOW
  vec2 uv = (ground - u_ground_region.xy) * u_ground_region.z + 0.5;
  if (uv.x >= 0.0 && uv.x <= 1.0 && uv.y >= 0.0 && uv.y <= 1.0) fraction = texture2D(u_ground_fraction, uv).rgb;
#endif
#ifdef NEAR_FLOOR_CAMERA
  camera_floor = cameraFloor(ground);
#endif
  vec3 from_ball = vec3(ground, 0.0) - u_ball_centre_w;
  float length_m = length(from_ball);
  if (length_m <= 1e-3) return direction;
  vec3 d = from_ball / length_m;
  // The ball's own parallax: ibl::nearFloorLookup's fixed-point steps.
  for (int step = 0; step < NEAR_FLOOR_BALL_STEPS; ++step) {
    vec3 half_vector = d + u_ball_to_eye_w;
    float half_length = length(half_vector);
    if (half_length <= 1e-3) break;
    from_ball = vec3(ground, 0.0) - (u_ball_centre_w + u_ball_radius_m * half_vector / half_length);
    length_m = length(from_ball);
    if (length_m <= 1e-3) break;
    d = from_ball / length_m;
  }
  return d;
}
#endif

#ifdef SELF_SHADOW_LIGHTS
// The object's shadow on itself, in the ratio form the ground's shadow uses
// (ibl/ground_shadow.hpp): the dome's lights carry the maps' energy, so the
// share of the diffuse light a point loses is what its hidden lights gave,
//   visibility = 1 - sum_i C_i max(0, n.L_i) (1 - V_i) / (pi D(n)),
// per channel, with V_i the lit share of a 2x2 percentage-closer test in
// light i's map of the object's near side (passes/ground_shadow.hpp:
// SelfShadowLight). Light from below the horizon (the floor) is in D(n)
// but in no dome light, so it is never hidden: the floor's bounce under a
// model stays. Where the dome and the maps disagree the ratio is clamped
// to [0, 1]. The lights' cones are not spread here: a self-shadow's edge
// is the map's texel, softened by the 2x2 test.
uniform sampler2D u_self_shadow_map[SELF_SHADOW_LIGHTS];
// Rows of the light's clip_from_world folded into [0, 1]: uv.x, uv.y, depth01.
uniform vec4 u_self_shadow_row0[SELF_SHADOW_LIGHTS];
uniform vec4 u_self_shadow_row1[SELF_SHADOW_LIGHTS];
uniform vec4 u_self_shadow_row2[SELF_SHADOW_LIGHTS];
uniform vec3 u_self_shadow_direction[SELF_SHADOW_LIGHTS];
uniform vec3 u_self_shadow_rgb[SELF_SHADOW_LIGHTS];
// x: one texel in uv; y: one texel's width in depth01 (width / depth / size).
uniform vec2 u_self_shadow_texel[SELF_SHADOW_LIGHTS];

float nearDepth(sampler2D map, vec2 uv) {
#ifdef SHADOW_DEPTH_PACKED
  return unpackDepth(texture2D(map, uv));
#else
  return texture2D(map, uv).r;
#endif
}

// The share of a point a light's near-side map says is lit: a 2x2
// percentage-closer test at its place in the map.
float litShare(sampler2D map, vec4 row0, vec4 row1, vec4 row2, vec2 texel, vec3 l, vec3 surface_normal, vec4 p) {
  vec2 uv = vec2(dot(row0, p), dot(row1, p));
  float depth = dot(row2, p);
  // Slope-scaled bias: across one texel the surface's own depth changes by
  // the texel's width times tan(angle to the light); 1.5 of that plus 1.5
  // texels keeps a lit surface from shadowing itself (acne) while a real
  // occluder further than two texels still shadows.
  float cos_surface = max(dot(surface_normal, l), 0.05);
  float tan_surface = min(sqrt(1.0 - cos_surface * cos_surface) / cos_surface, 8.0);
  float bias = (1.5 + 1.5 * tan_surface) * texel.y;
  float half_texel = 0.5 * texel.x;
  float lit = 0.0;
  lit += nearDepth(map, uv + vec2(-half_texel, -half_texel)) + bias >= depth ? 0.25 : 0.0;
  lit += nearDepth(map, uv + vec2(half_texel, -half_texel)) + bias >= depth ? 0.25 : 0.0;
  lit += nearDepth(map, uv + vec2(-half_texel, half_texel)) + bias >= depth ? 0.25 : 0.0;
  lit += nearDepth(map, uv + vec2(half_texel, half_texel)) + bias >= depth ? 0.25 : 0.0;
  return lit;
}

#ifdef SELF_SHADOW_FLOOR_LIGHTS
// The floor's light (passes/ground_shadow's floorSelfShadows: the object
// seen from directions below the horizon). The floor is Lambertian and,
// under a model, uniform enough that a normal n receives E_down (1 - n.z) / 2
// of it, E_down = pi D(-Z) being the irradiance of a face looking straight
// down. It is shared among the floor directions in front of the point,
// by max(0, n.L_k), and each share is hidden where the point is not the
// object's surface nearest the floor along L_k (the inside of a bowl sees
// its own walls there, not the floor).
uniform sampler2D u_self_shadow_floor_map[SELF_SHADOW_FLOOR_LIGHTS];
uniform vec4 u_self_shadow_floor_row0[SELF_SHADOW_FLOOR_LIGHTS];
uniform vec4 u_self_shadow_floor_row1[SELF_SHADOW_FLOOR_LIGHTS];
uniform vec4 u_self_shadow_floor_row2[SELF_SHADOW_FLOOR_LIGHTS];
uniform vec3 u_self_shadow_floor_direction[SELF_SHADOW_FLOOR_LIGHTS];
uniform vec2 u_self_shadow_floor_texel[SELF_SHADOW_FLOOR_LIGHTS];
#endif

vec3 selfShadowVisibility(vec3 position, vec3 surface_normal, vec3 n, vec3 diffuse) {
  vec3 hidden = vec3(0.0);
  vec4 p = vec4(position, 1.0);
  for (int i = 0; i < SELF_SHADOW_LIGHTS; ++i) {
    vec3 l = u_self_shadow_direction[i];
    float cos_shading = dot(n, l);
    if (cos_shading <= 0.0) continue;
    float lit = litShare(u_self_shadow_map[i], u_self_shadow_row0[i], u_self_shadow_row1[i], u_self_shadow_row2[i],
                         u_self_shadow_texel[i], l, surface_normal, p);
    hidden += u_self_shadow_rgb[i] * cos_shading * (1.0 - lit);
  }
#ifdef SELF_SHADOW_FLOOR_LIGHTS
  float floor_share = 0.5 - 0.5 * n.z;
  if (floor_share > 0.0) {
    float weight_sum = 0.0;
    float hidden_weight = 0.0;
    for (int k = 0; k < SELF_SHADOW_FLOOR_LIGHTS; ++k) {
      vec3 l = u_self_shadow_floor_direction[k];
      float weight = max(dot(n, l), 0.0);
      if (weight <= 0.0) continue;
      float lit = litShare(u_self_shadow_floor_map[k], u_self_shadow_floor_row0[k], u_self_shadow_floor_row1[k],
                           u_self_shadow_floor_row2[k], u_self_shadow_floor_texel[k], l, surface_normal, p);
      weight_sum += weight;
      hidden_weight += weight * (1.0 - lit);
    }
    vec3 e_down =
        3.14159265 * sampleCubeBilinear(u_diffuse_map, vec3(0.0, 0.0, -1.0), u_diffuse_face_size, u_diffuse_scale).rgb;
    if (weight_sum > 0.0) hidden += e_down * floor_share * hidden_weight / weight_sum;
  }
#endif
  return clamp(1.0 - hidden / max(3.14159265 * diffuse, vec3(1e-4)), 0.0, 1.0);
}
#endif

vec2 transformUv(mat3 transform, vec2 uv) { return (transform * vec3(uv, 1.0)).xy; }

// The continuous place of alpha on the ladder: k + t between rungs k and
// k + 1 (the alphas increase, so the clamped fractions add up to it).
float ladderPosition(float alpha) {
  float position = 0.0;
  for (int k = 0; k < DIFFUSE_RUNG; ++k)
    position += clamp((alpha - u_rung_alpha[k]) / (u_rung_alpha[k + 1] - u_rung_alpha[k]), 0.0, 1.0);
  return position;
}

float rungWeight(float rung, float position) { return max(1.0 - abs(position - rung), 0.0); }

void main() {
  vec4 base_color = u_base_color_factor;
#ifdef BASE_COLOR_TEXTURE
  vec4 base_texel = texture2D(u_base_color_texture, transformUv(u_base_color_uv_transform, BASE_COLOR_UV));
  base_color *= vec4(srgbToLinear(base_texel.rgb), base_texel.a);
#endif
#ifdef HAS_COLOR
  base_color *= v_color;
#endif
  float alpha = base_color.a;
#ifdef ALPHA_MASK
  if (alpha < u_alpha_cutoff) discard;
  alpha = 1.0;
#endif
#if !defined(ALPHA_MASK) && !defined(ALPHA_BLEND)
  alpha = 1.0;
#endif
  float metallic = u_metallic_factor;
  float roughness = u_roughness_factor;
#ifdef METALLIC_ROUGHNESS_TEXTURE
  vec4 metallic_roughness =
      texture2D(u_metallic_roughness_texture, transformUv(u_metallic_roughness_uv_transform, METALLIC_ROUGHNESS_UV));
  roughness *= metallic_roughness.g;
  metallic *= metallic_roughness.b;
#endif
  metallic = clamp(metallic, 0.0, 1.0);
  roughness = clamp(roughness, 0.0, 1.0);

  vec3 n = normalize(v_normal_w);
#ifdef NORMAL_TEXTURE
  vec3 t = normalize(v_tangent_w.xyz - n * dot(n, v_tangent_w.xyz));
  vec3 b = cross(n, t) * (v_tangent_w.w < 0.0 ? -1.0 : 1.0);
  vec3 tangent_normal = texture2D(u_normal_texture, transformUv(u_normal_uv_transform, NORMAL_UV)).xyz * 2.0 - 1.0;
  tangent_normal.xy *= u_normal_scale;
#endif
#ifdef DOUBLE_SIDED
  // The back of a double-sided surface is lit as its own front.
  if (!gl_FrontFacing) n = -n;
#endif
#ifdef NORMAL_TEXTURE
#ifdef DOUBLE_SIDED
  if (!gl_FrontFacing) {
    t = -t;
    b = -b;
  }
#endif
  n = normalize(tangent_normal.x * t + tangent_normal.y * b + tangent_normal.z * n);
#endif
  vec3 to_eye = normalize(v_to_eye_w);
  float n_dot_v = max(dot(n, to_eye), 1e-4);

  vec3 c_diff = base_color.rgb * (1.0 - metallic);
  vec3 f0 = mix(vec3(0.04), base_color.rgb, metallic);
  vec2 brdf_coord = (vec2(roughness, sqrt(n_dot_v)) * (u_brdf_table_size - 1.0) + 0.5) / u_brdf_table_size;
  vec4 brdf = texture2D(u_brdf_table, brdf_coord);
  vec3 specular_reflectance = f0 * brdf.r + brdf.a;

  vec3 diffuse = sampleCubeBilinear(u_diffuse_map, n, u_diffuse_face_size, u_diffuse_scale).rgb;
  for (int k = 0; k < 4; ++k) diffuse += u_clipped_diffuse_rgb[k] * max(dot(n, u_clipped_direction_w[k]), 0.0);
  diffuse += u_lamp_diffuse_rgb * max(dot(n, u_lamp_direction_w), 0.0);

  vec3 mirror = reflect(-to_eye, n);
  vec3 floor_fraction = vec3(1.0);
  vec4 camera_floor = vec4(0.0);
#ifdef NEAR_FLOOR
  mirror = nearFloorDirection(v_position_w, mirror, floor_fraction, camera_floor);
#endif
  float position = clamp(ladderPosition(roughness * roughness), float(RUNG_FIRST), float(RUNG_LAST));
  vec3 specular = vec3(0.0);
#if RUNG_FIRST == 0
  specular += rungWeight(0.0, position) *
              mix(sampleCubeBilinear(u_reflection_map, mirror, u_reflection_face_size, u_reflection_scale).rgb,
                  camera_floor.rgb, camera_floor.a);
#endif
#ifdef READS_GLOSSY0
  specular += rungWeight(1.0, position) *
              sampleCubeBilinear(u_glossy0_map, mirror, u_glossy0_face_size, u_glossy0_scale).rgb;
#endif
#ifdef READS_GLOSSY1
  specular += rungWeight(2.0, position) *
              sampleCubeBilinear(u_glossy1_map, mirror, u_glossy1_face_size, u_glossy1_scale).rgb;
#endif
  specular *= floor_fraction;
#if RUNG_LAST == DIFFUSE_RUNG
  specular += rungWeight(float(DIFFUSE_RUNG), position) * diffuse;
#endif

  float occlusion = 1.0;
#ifdef OCCLUSION_TEXTURE
  occlusion = 1.0 + u_occlusion_strength *
                        (texture2D(u_occlusion_texture, transformUv(u_occlusion_uv_transform, OCCLUSION_UV)).r - 1.0);
#endif
  vec3 emissive = u_emissive_factor;
#ifdef EMISSIVE_TEXTURE
  emissive *= srgbToLinear(texture2D(u_emissive_texture, transformUv(u_emissive_uv_transform, EMISSIVE_UV)).rgb);
#endif
#ifdef SELF_SHADOW_LIGHTS
  // The specular light is hidden as much as the diffuse (the lights' lobes
  // about the reflection are not resolved): a common approximation, and
  // the one that keeps a shadowed crevice from showing the sky in a metal.
  vec3 visibility = selfShadowVisibility(v_position_w, normalize(v_normal_w), n, diffuse);
  // Light the model bounces onto itself where it hides the room:
  // ibl::multiBounceVisibility (Jimenez et al.'s fit, 2016), with the
  // surface's own reflectance standing for its surroundings'.
  vec3 albedo = clamp(c_diff + f0, 0.0, 1.0);
  vec3 bounce_a = 2.0404 * albedo - 0.3324;
  vec3 bounce_b = -4.7951 * albedo + 0.6417;
  vec3 bounce_c = 2.7552 * albedo + 0.6903;
  visibility = max(visibility, ((visibility * bounce_a + bounce_b) * visibility + bounce_c) * visibility);
  vec3 color = occlusion * visibility * (c_diff * (1.0 - specular_reflectance) * diffuse + specular_reflectance * specular) + emissive;
#else
  vec3 color = occlusion * (c_diff * (1.0 - specular_reflectance) * diffuse + specular_reflectance * specular) + emissive;
#endif
  gl_FragColor = vec4(cameraOutput(color), alpha);
}
