// The camera's transfer (ibl::CameraTransfer), chosen when the program is
// built: sRGB unless CAMERA_TRANSFER_GAMMA or CAMERA_TRANSFER_LINEAR.
// Needs color_transfer.glsl first.
#if defined(CAMERA_TRANSFER_LINEAR)
vec3 decodeCamera(vec3 encoded) { return clamp(encoded, 0.0, 1.0); }
vec3 encodeCamera(vec3 linear) { return clamp(linear, 0.0, 1.0); }
#elif defined(CAMERA_TRANSFER_GAMMA)
uniform float u_camera_gamma;
vec3 decodeCamera(vec3 encoded) { return pow(clamp(encoded, 0.0, 1.0), vec3(u_camera_gamma)); }
vec3 encodeCamera(vec3 linear) { return pow(clamp(linear, 0.0, 1.0), vec3(1.0 / u_camera_gamma)); }
#else
vec3 decodeCamera(vec3 encoded) { return srgbToLinear(encoded); }
vec3 encodeCamera(vec3 linear) { return linearToSrgb(linear); }
#endif

// encode(decode(encoded) * m): light scaled by m in the camera's own
// values. A power law takes one pow for it, encoded m^(1/gamma), not two;
// sRGB decodes by color_transfer.glsl's polynomial and encodes with one
// pow (a shortcut on its power segment, (encoded + 0.055) m^(1/2.4) -
// 0.055, needs that pow too and another for the toe: a GPU without real
// branches, llvmpipe, pays for both).
vec3 scaleEncodedCamera(vec3 encoded, vec3 m) {
#if defined(CAMERA_TRANSFER_GAMMA)
  return clamp(clamp(encoded, 0.0, 1.0) * pow(m, vec3(1.0 / u_camera_gamma)), 0.0, 1.0);
#else
  return encodeCamera(decodeCamera(encoded) * m);
#endif
}
