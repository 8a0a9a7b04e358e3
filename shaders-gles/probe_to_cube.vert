#version 100
// Full-screen quad over one cube face (as cube_face.vert), carrying the
// texel's direction already turned into the camera's frame: the direction
// is affine in the quad's position, so the rasteriser interpolates it
// exactly, and the per-texel rotation (9 multiply-adds a texel) becomes 3
// rotated axes per face on the CPU.
attribute vec2 a_position;
uniform vec3 u_face_center_cam;  // R_cam_from_world * (direction at the face centre)
uniform vec3 u_face_s_axis_cam;  // R_cam_from_world * d(direction) / d(2s - 1)
uniform vec3 u_face_t_axis_cam;  // R_cam_from_world * d(direction) / d(2t - 1)
varying vec3 v_direction_cam;    // unnormalised

void main() {
  v_direction_cam = u_face_center_cam + a_position.x * u_face_s_axis_cam + a_position.y * u_face_t_axis_cam;
  gl_Position = vec4(a_position, 0.0, 1.0);
}
