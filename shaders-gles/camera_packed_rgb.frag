#version 100
// A camera's packed RGB plane (RGB888, BGR888, XRGB8888) to the RGB frame
// texture. The plane is uploaded as bytes (RGB, or RGBA for XRGB8888), so
// a format whose bytes run B, G, R (PL_BLUE_FIRST: RGB888, XRGB8888 in
// DRM's little-endian order) is swapped here; bytes in, bytes out.
varying vec2 v_texcoord;
uniform sampler2D u_packed;

void main() {
  vec3 texel = texture2D(u_packed, v_texcoord).rgb;
#ifdef PL_BLUE_FIRST
  texel = texel.bgr;
#endif
  gl_FragColor = vec4(texel, 1.0);
}
