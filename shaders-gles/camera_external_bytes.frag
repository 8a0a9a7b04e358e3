#version 100
#extension GL_OES_EGL_image_external : require
// A packed 24-bit RGB camera buffer (RGB888, BGR888) imported in place as
// one byte a texel (DRM's R8, three texels a pixel): drivers that import no
// 24-bit RGB dmabuf (Mesa's llvmpipe) import that. Each output pixel reads
// its three bytes at their texel centres (the image is sampled NEAREST) and
// puts them in R, G, B order as camera_packed_rgb.frag does: bytes in,
// bytes out. Texel addresses reach 3 x 4096: highp, which the code asks
// for before it uses this pass.
#ifdef GL_FRAGMENT_PRECISION_HIGH
precision highp float;
#else
precision mediump float;
#endif
varying vec2 v_texcoord;
uniform samplerExternalOES u_bytes;
uniform float u_width_px;

void main() {
  float pixel = floor(gl_FragCoord.x);
  float texel_width = 1.0 / (3.0 * u_width_px);
  float first = (3.0 * pixel + 0.5) * texel_width;
  vec3 bytes = vec3(texture2D(u_bytes, vec2(first, v_texcoord.y)).r,
                    texture2D(u_bytes, vec2(first + texel_width, v_texcoord.y)).r,
                    texture2D(u_bytes, vec2(first + 2.0 * texel_width, v_texcoord.y)).r);
#ifdef PL_BLUE_FIRST
  bytes = bytes.bgr;
#endif
  gl_FragColor = vec4(bytes, 1.0);
}
