#version 100
// Where the object's shadow from the lamp falls: the lamp hidden (0) in a
// texture cleared to 1.
precision mediump float;

void main() {
  gl_FragColor = vec4(0.0);
}
