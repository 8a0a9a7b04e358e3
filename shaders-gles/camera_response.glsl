// What the frame went through on its way out of the camera, applied to an
// object rendered in linear light: the exposure and white balance since its
// light was measured, the camera's transfer (camera_transfer.glsl) and, with MATCH_SENSOR_NOISE, noise of the frame's own statistic
// (passes/camera_response.hpp, ibl/sensor_noise.hpp). Needs
// color_transfer.glsl and camera_transfer.glsl first.
//
// The noise is Gaussian, independent per channel and pixel, of sigma
// ibl::addedNoiseSigmaCode: linear in the 8-bit code between the frame's
// two measured levels (the tag's black and white ink), constant beyond.
// Its samples come from a 128 x 128 texture of N(0, 1) values (code
// 127.5 + 32 z), read one texel a pixel at an offset that moves every frame,
// so that the grain changes from frame to frame as the sensor's does.
#ifdef MATCH_SENSOR_NOISE
uniform sampler2D u_noise_normal;
uniform vec2 u_noise_offset;             // in texture units, a whole texel each frame
uniform vec3 u_noise_dark_code;          // the levels' 8-bit codes, per channel
uniform vec3 u_noise_bright_code;
uniform vec3 u_noise_dark_sigma_code;    // the sigma to add at each level
uniform vec3 u_noise_bright_sigma_code;

// The noise to add to an encoded colour in [0, 1], in the same units. At
// 16-bit mediump the code (encoded x 255) keeps 0.12 of a code step, far
// under what moves sigma.
vec3 sensorNoise(vec3 encoded) {
  vec3 z = (texture2D(u_noise_normal, gl_FragCoord.xy * (1.0 / 128.0) + u_noise_offset).rgb * 255.0 - 127.5) *
           (1.0 / 32.0);
  vec3 span = max(u_noise_bright_code - u_noise_dark_code, vec3(1.0e-3));
  vec3 toward_bright = clamp((encoded * 255.0 - u_noise_dark_code) / span, 0.0, 1.0);
  vec3 sigma_code = mix(u_noise_dark_sigma_code, u_noise_bright_sigma_code, toward_bright);
  return z * sigma_code * (1.0 / 255.0);
}
#endif

// The camera's exposure and white balance in this frame over those of the
// frame the object's light was measured in (stages/frame_response.hpp), per
// channel: 1 while they have not moved.
uniform vec3 u_response_gain_rgb;

#ifdef BLOOM_BRIGHT_PASS
// The bloom's bright pass (passes/object_bloom): the light beyond white,
// e = max(light - 1, 0), stored as sqrt(e / BLOOM_RANGE) (object_bloom.frag
// decodes it).
vec3 cameraOutput(vec3 linear) {
  vec3 beyond_white = max(linear * u_response_gain_rgb - 1.0, 0.0);
  return sqrt(clamp(beyond_white / BLOOM_RANGE, 0.0, 1.0));
}
#else
// The encoded colour the camera would have written for `linear` (in the
// units of the object's light).
vec3 cameraOutput(vec3 linear) {
  vec3 encoded = encodeCamera(linear * u_response_gain_rgb);
#ifdef MATCH_SENSOR_NOISE
  encoded += sensorNoise(encoded);
#endif
  return encoded;
}
#endif
