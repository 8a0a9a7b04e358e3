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
// both the value and the result are past its linear toe (0.04045).
//
// Where either is in the toe, sRGB is still exact with one more pow (a
// GPU without real branches, llvmpipe, pays for every case at every pixel,
// so the cases share it): with L = decode(encoded) m,
//   encoded in the toe:  L = encoded m / 12.92, and the result is 12.92 L
//                        below L = 0.0031308, else 1.055 L^(1/2.4) - 0.055;
//   the result in the toe: 12.92 L, L = ((scaled + 0.055) / 1.055)^2.4
//                        (scaled is 1.055 L^(1/2.4) - 0.055 there too).
vec3 scaleEncodedCamera(vec3 encoded, vec3 m, vec3 root) {
#if defined(CAMERA_TRANSFER_LINEAR)
  return clamp(encoded * m, 0.0, 1.0);
#elif defined(CAMERA_TRANSFER_GAMMA)
  return clamp(encoded * root, 0.0, 1.0);
#else
  vec3 e = clamp(encoded, 0.0, 1.0);
  vec3 scaled = (e + 0.055) * root - 0.055;
  vec3 encoded_in_toe = step(e, vec3(0.04045));  // 1: in the toe
  vec3 toe_linear = e * m * (1.0 / 12.92);
  vec3 base = mix(max((scaled + 0.055) * (1.0 / 1.055), 0.0), toe_linear, encoded_in_toe);
  vec3 powered = pow(base, mix(vec3(2.4), vec3(1.0 / 2.4), encoded_in_toe));
  vec3 from_toe = mix(1.055 * powered - 0.055, 12.92 * toe_linear, step(toe_linear, vec3(0.0031308)));
  vec3 into_toe = 12.92 * powered;
  vec3 result = mix(mix(scaled, into_toe, step(scaled, vec3(0.04045))), from_toe, encoded_in_toe);
  return clamp(result, 0.0, 1.0);
#endif
}
