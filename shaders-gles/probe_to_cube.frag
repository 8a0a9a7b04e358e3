#version 100
// Stage 2: the mirror ball's image to one face of a world-aligned cube map,
// the maths of ibl::probeImageToCubeMap.
//
// Precision: geometry is done in coordinates centred on the ball and scaled
// by its radius (eye at ~10-30 radii), and the projection is written relative
// to the ball centre's (exactly precomputed) image position, so every mediump
// quantity is O(1) or a small offset; no metre-scale positions are added to
// centimetre-scale ones here.
#include "color_transfer.glsl"
#include "camera_transfer.glsl"
#include "camera_projection.glsl"
#include "cube_storage.glsl"

#ifndef NORMAL_ITERATIONS
#define NORMAL_ITERATIONS 1
#endif

// Compared squared: a bisector shorter than the length is the blind spot.
#ifdef PL_FRAGMENT_HIGHP
#define BLIND_SPOT_LENGTH_SQUARED 1e-12
#else
// 1e-6 is below mediump's resolution next to 1; this only widens the blind
// spot (already 0) by a few milliradians.
#define BLIND_SPOT_LENGTH_SQUARED 1e-6
#endif

varying vec3 v_direction_cam;  // probe_to_cube.vert: the texel's direction, camera frame

// Everything below is in the camera's frame (rotation about the ball
// centre changes none of the maths, and the CPU turns the face axes once).
uniform vec3 u_eye_ball;                 // (camera centre - ball centre) / radius = -centre_cam / radius
uniform vec3 u_eye_direction;            // normalize(u_eye_ball), computed once on the CPU
uniform vec2 u_center_normalized;        // ball centre in the camera: (x/z, y/z)
uniform float u_radius_over_depth;       // radius / ball centre's camera z
uniform vec4 u_distortion;               // k1 k2 p1 p2
uniform float u_distortion_k3;
uniform float u_center_r2;         // |u_center_normalized|^2
uniform float u_center_radial;     // the radial distortion factor there
uniform vec2 u_focal_over_size;    // (fx / width, fy / height)
// Texcoord of the ball centre's projection as a value that 11 significant
// bits hold exactly, plus the rest: mediump would otherwise round the
// uniform itself by up to half an ulp (0.16 px) before the sum rounds again.
uniform vec2 u_center_texcoord;
uniform vec2 u_center_texcoord_residual;
uniform sampler2D u_camera;        // sRGB bytes, LINEAR, CLAMP_TO_EDGE
uniform float u_inverse_reflectance;
uniform float u_storage_scale;     // linear_scale of cube_storage.glsl

void main() {
  vec3 r = normalize(v_direction_cam);
  // Newton's steps on the ball normal, as ibl::reflectedDirectionToPixel; in
  // ball units the surface point is the normal itself. The seed normalize
  // shares its squared length with the blind-spot test.
  vec3 bisector = u_eye_direction + r;
  float length_squared = dot(bisector, bisector);
  bool blind = length_squared < BLIND_SPOT_LENGTH_SQUARED;
  vec3 normal = bisector * inversesqrt(length_squared);
  for (int i = 0; i < NORMAL_ITERATIONS; ++i) {
    // (eye - n) + |eye - n| r points along normalize(eye - n) + r with one
    // square root instead of a second normalize.
    vec3 to_eye = u_eye_ball - normal;
    float to_eye_squared = dot(to_eye, to_eye);
    bisector = to_eye + sqrt(to_eye_squared) * r;
    length_squared = dot(bisector, bisector);
    blind = blind || length_squared < BLIND_SPOT_LENGTH_SQUARED * to_eye_squared;
    vec3 target = bisector * inversesqrt(length_squared);
    // Newton's step length, 2|u|^2 / (2|u|^2 + eye.n - 1) written without
    // doubling |u|^2, which a 16-bit mediump float holds only up to 65504.
    float relaxation = to_eye_squared / (to_eye_squared + 0.5 * (dot(u_eye_ball, normal) - 1.0));
    normal += relaxation * (target - normal);
    normal *= 1.5 - 0.5 * dot(normal, normal);  // the chord back to unit length
  }
  // Visible exactly when the normal faces the eye (convex ball).
  blind = blind || dot(normal, u_eye_ball - normal) <= 0.0;
  // Camera point = centre_cam + radius * R n; divided by the centre's depth:
  vec3 offset = u_radius_over_depth * normal;
  float depth_ratio = 1.0 + offset.z;
  blind = blind || depth_ratio <= 0.0;
  // The point's normalised position relative to the centre's,
  // (c + offset.xy) / (1 + offset.z) - c, and its distortion likewise, so
  // that nothing of the centre's O(1) size is added in and taken out again
  // (at 16 bits that alone moved the sample by 0.3 px).
  vec2 normalized_delta = (offset.xy - u_center_normalized * offset.z) / max(depth_ratio, 1e-3);
  vec2 distorted_delta = distortionDelta(u_center_normalized, normalized_delta, u_center_r2, u_center_radial,
                                         u_distortion, u_distortion_k3);
  vec2 texcoord = u_center_texcoord + (distorted_delta * u_focal_over_size + u_center_texcoord_residual);
  vec3 linear = decodeCamera(texture2D(u_camera, texcoord).rgb) * u_inverse_reflectance;
  gl_FragColor = blind ? vec4(0.0) : encodeCubeTexel(linear, 1.0, u_storage_scale);
}
