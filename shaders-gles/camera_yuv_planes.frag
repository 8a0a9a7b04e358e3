#version 100
// YUV 4:2:0 planes to sRGB bytes. I420: three LUMINANCE textures; NV12
// (PL_NV12): LUMINANCE, then the Cb Cr pairs as LUMINANCE_ALPHA (.r, .a).
// rgb = M * code + offset, with M and offset built by core/ycbcr.cpp from
// the stream's matrix and range. Codes are in [0, 1]: mediump's 10-bit
// mantissa keeps them within 1/2048, a fraction of one 8-bit output step.
varying vec2 v_texcoord;
uniform sampler2D u_luma;
uniform sampler2D u_cb;
uniform sampler2D u_cr;  // unused for NV12
// The chroma planes are ceil(w/2) wide: for odd sizes their texcoord is
// scaled so that chroma sample k stays centred on luma pixels 2k, 2k+1.
uniform vec2 u_chroma_scale;
uniform mat3 u_ycbcr_to_rgb;
uniform vec3 u_offset;

void main() {
  vec2 chroma_texcoord = v_texcoord * u_chroma_scale;
#ifdef PL_NV12
  vec2 chroma = texture2D(u_cb, chroma_texcoord).ra;
#else
  vec2 chroma = vec2(texture2D(u_cb, chroma_texcoord).r, texture2D(u_cr, chroma_texcoord).r);
#endif
  vec3 code = vec3(texture2D(u_luma, v_texcoord).r, chroma);
  gl_FragColor = vec4(clamp(u_ycbcr_to_rgb * code + u_offset, 0.0, 1.0), 1.0);
}
