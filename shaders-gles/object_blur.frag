#version 100
// One pass of the object layer's separable Gaussian blur (passes/
// object_blur), in linear light: TAPS texels either side along u_step,
// weights u_weight (centre first). The layers hold the object's colour
// sRGB-encoded and premultiplied by its coverage (as GL blends them); each
// tap is decoded to linear light times coverage, so colour and coverage
// blur as the lens blurred the frame's light. The horizontal pass stores
// its result encoded and premultiplied again (8-bit linear would band in
// the darks).
//
// COMPOSITE (the vertical pass): the blurred object over u_base, the frame
// as drawn before the object (video and shadow), mixed in linear light by
// the blurred coverage, as the camera would have mixed the object's light
// with the room's: out = encode(L + (1 - A) decode(base)). With
// MATCH_SENSOR_NOISE the frame's noise is then added, after the blur as a
// sensor adds it after the lens, times the object's share A.
//
// Encoded and decoded with the camera's transfer (camera_transfer.glsl).
//
// Precision: the taps' places are uv + k step, k up to 12; at 16-bit
// mediump a place near 1 keeps 2^-11, 0.3 of a texel of a 640-texel
// layer, which only moves a bilinear tap's weight between two neighbours.
// With PL_FRAGMENT_HIGHP they are highp.
#include "color_transfer.glsl"
#include "camera_transfer.glsl"
#include "camera_response.glsl"

#ifdef PL_FRAGMENT_HIGHP
#define PLACE highp
#else
#define PLACE mediump
#endif

varying PLACE vec2 v_uv;
uniform sampler2D u_layer;
uniform PLACE vec2 u_step;            // one texel along the pass's axis
uniform float u_weight[TAPS + 1];     // the centre's, then each side's
#ifdef COMPOSITE
uniform sampler2D u_base;
#endif

// A tap's linear light times its coverage, and its coverage.
vec4 linearTap(PLACE vec2 uv) {
  vec4 texel = texture2D(u_layer, uv);
  return vec4(decodeCamera(texel.rgb / max(texel.a, 1.0 / 255.0)) * texel.a, texel.a);
}

void main() {
  vec4 sum = u_weight[0] * linearTap(v_uv);
  for (int k = 1; k <= TAPS; ++k) {
    PLACE vec2 offset = float(k) * u_step;
    sum += u_weight[k] * (linearTap(v_uv + offset) + linearTap(v_uv - offset));
  }
#ifdef COMPOSITE
  vec3 base = decodeCamera(texture2D(u_base, v_uv).rgb);
  vec3 encoded = encodeCamera(sum.rgb + (1.0 - sum.a) * base);
#ifdef MATCH_SENSOR_NOISE
  encoded += sum.a * sensorNoise(encoded);
#endif
  gl_FragColor = vec4(encoded, 1.0);
#else
  gl_FragColor = vec4(encodeCamera(sum.rgb / max(sum.a, 1.0 / 4096.0)) * sum.a, sum.a);
#endif
}
