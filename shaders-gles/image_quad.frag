#version 100
// Camera background and overlays: the texture as stored (sRGB bytes in, sRGB
// bytes out, no round trip through linear light).
varying vec2 v_texcoord;
uniform sampler2D u_image;

void main() {
  gl_FragColor = texture2D(u_image, v_texcoord);
}
