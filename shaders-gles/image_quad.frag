#version 100
// Camera background and overlays: the texture as stored (sRGB bytes in, sRGB
// bytes out, no round trip through linear light). With EXPOSURE_GAIN, the
// camera's bytes decoded, times the gain (the frame darkened as a shorter
// exposure would: stages/lamp_exposure.hpp), encoded again.
#ifdef EXPOSURE_GAIN
#include "color_transfer.glsl"
#include "camera_transfer.glsl"
uniform float u_exposure_gain;
#endif
varying vec2 v_texcoord;
uniform sampler2D u_image;

void main() {
#ifdef EXPOSURE_GAIN
  gl_FragColor = vec4(encodeCamera(u_exposure_gain * decodeCamera(texture2D(u_image, v_texcoord).rgb)), 1.0);
#else
  gl_FragColor = texture2D(u_image, v_texcoord);
#endif
}
