#version 100
// The lens's glare around the virtual object's light above white (passes/
// object_bloom): one pass of a separable Gaussian over the bright layer,
// which holds, at a fraction of the frame's resolution, the object's light
// beyond white, e, stored as sqrt(e / BLOOM_RANGE) (8 bits keep the faint
// halo's tail: a step near 0 is BLOOM_RANGE / 255^2 of white). Each tap is
// decoded to light, so the halo spreads light, not bytes.
//
// COMPOSITE (the vertical pass, drawn at the frame's resolution over the
// object's region, the taps reading the layer bilinearly): the spread light
// added to u_base, the frame as drawn so far, in linear light, and encoded
// with the camera's transfer: out = encode(decode(base) + G * e). Light
// that falls on pixels already white is lost there, as in the camera.
//
// Precision: as object_blur.frag (the taps' places in PLACE).
#include "color_transfer.glsl"
#include "camera_transfer.glsl"

#ifdef PL_FRAGMENT_HIGHP
#define PLACE highp
#else
#define PLACE mediump
#endif

varying PLACE vec2 v_uv;
uniform sampler2D u_layer;
uniform PLACE vec2 u_step;            // one layer texel along the pass's axis
uniform float u_weight[TAPS + 1];     // the centre's, then each side's
#ifdef COMPOSITE
uniform sampler2D u_base;
#endif

vec3 lightAt(PLACE vec2 uv) {
  vec3 stored = texture2D(u_layer, uv).rgb;
  return stored * stored * BLOOM_RANGE;
}

void main() {
  vec3 sum = u_weight[0] * lightAt(v_uv);
  for (int k = 1; k <= TAPS; ++k) {
    PLACE vec2 offset = float(k) * u_step;
    sum += u_weight[k] * (lightAt(v_uv + offset) + lightAt(v_uv - offset));
  }
#ifdef COMPOSITE
  vec3 base = decodeCamera(texture2D(u_base, v_uv).rgb);
  gl_FragColor = vec4(encodeCamera(base + sum), 1.0);
#else
  gl_FragColor = vec4(sqrt(clamp(sum / BLOOM_RANGE, 0.0, 1.0)), 1.0);
#endif
}
