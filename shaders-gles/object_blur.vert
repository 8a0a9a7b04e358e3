#version 100
// The object's blur layer (passes/object_blur) over the frame, or into its
// horizontal pass's target: a full-screen quad whose texture coordinate is
// NDC * 0.5 + 0.5 with no flip (the layer was drawn with the frame's NDC).
// Made here in highp; the fragment shader adds the taps' offsets.
attribute vec2 a_position;
varying vec2 v_uv;

void main() {
  v_uv = 0.5 * a_position + 0.5;
  gl_Position = vec4(a_position, 0.0, 1.0);
}
