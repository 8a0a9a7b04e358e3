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
