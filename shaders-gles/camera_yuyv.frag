#version 100
// YUYV (4:2:2, one plane of Y'0 Cb Y'1 Cr per pixel pair) to sRGB bytes.
// The plane is uploaded twice, the same bytes: as LUMINANCE_ALPHA one texel
// a pixel (.r is its Y'), and as RGBA one texel a pair (.g Cb, .a Cr).
// Chroma sample k sits on pixel 2k (co-sited, as BT.601 and V4L2 place
// it): u_chroma_offset moves the chroma lookup so that GL_LINEAR reads
// sample k on pixel 2k and halfway to k + 1 on pixel 2k + 1.
// rgb = M * code + offset as for the 4:2:0 planes (core/ycbcr.cpp).
varying vec2 v_texcoord;
uniform sampler2D u_luma;
uniform sampler2D u_pairs;
uniform vec2 u_chroma_scale;
uniform vec2 u_chroma_offset;
uniform mat3 u_ycbcr_to_rgb;
uniform vec3 u_offset;

void main() {
  vec2 chroma = texture2D(u_pairs, v_texcoord * u_chroma_scale + u_chroma_offset).ga;
  vec3 code = vec3(texture2D(u_luma, v_texcoord).r, chroma);
  gl_FragColor = vec4(clamp(u_ycbcr_to_rgb * code + u_offset, 0.0, 1.0), 1.0);
}
