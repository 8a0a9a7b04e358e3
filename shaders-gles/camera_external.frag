#version 100
#extension GL_OES_EGL_image_external : require
// A camera buffer imported in place (EGL_EXT_image_dma_buf_import): the
// driver samples the Y'CbCr planes and converts them with the colour-space
// hints given at import; this pass copies the result into the RGB frame
// texture that every later stage reads.
varying vec2 v_texcoord;
uniform samplerExternalOES u_image;

void main() {
  gl_FragColor = vec4(texture2D(u_image, v_texcoord).rgb, 1.0);
}
