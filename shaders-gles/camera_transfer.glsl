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

// encode(decode(encoded) * m), light scaled by m in the camera's own
// values, given root = m^(1 / the transfer's exponent) (1/2.4 for sRGB,
// 1/gamma, 1 for linear): for a power law that is encoded * root, and for
// sRGB's power segment (encoded + 0.055) * root - 0.055, exactly, where
// both the value and the result are past its linear toe (0.04045); the toe
// takes the whole way round. A pass that scales by a smooth m can so make
// the root per vertex and skip two pows a pixel.
vec3 scaleEncodedCamera(vec3 encoded, vec3 m, vec3 root) {
#if defined(CAMERA_TRANSFER_LINEAR)
  return clamp(encoded * m, 0.0, 1.0);
#elif defined(CAMERA_TRANSFER_GAMMA)
  return clamp(encoded * root, 0.0, 1.0);
#else
  vec3 scaled = (encoded + 0.055) * root - 0.055;
  if (all(greaterThanEqual(encoded, vec3(0.04045))) && all(greaterThanEqual(scaled, vec3(0.04045))))
    return clamp(scaled, 0.0, 1.0);
  return encodeCamera(decodeCamera(encoded) * m);
#endif
}

