#version 100
// With OES_depth_texture the depth attachment holds the depth and the
// colour is unused; otherwise (SHADOW_DEPTH_PACKED) depth goes into RGBA8.
#include "depth_packing.glsl"
varying float v_depth01;

void main() {
#ifdef SHADOW_DEPTH_PACKED
  gl_FragColor = packDepth(v_depth01);
#else
  gl_FragColor = vec4(v_depth01);
#endif
}
