#include "passes/object_uniforms.hpp"

#include <glm/gtc/type_ptr.hpp>

namespace probelight::passes {

void setCameraProjectionUniforms(const gles::Program& program, const CameraIntrinsics& camera,
                                 const PoseCamFromWorld& pose, double near_m, double far_m) {
  const glm::vec3 eye_w(pose.cameraCenterWorld());
  const glm::mat3 rotation(pose.R_cam_from_world);
  const glm::vec3 translation(pose.t_cam_from_world);
  glUniformMatrix3fv(program.uniform("u_rotation_cam_from_world"), 1, GL_FALSE, glm::value_ptr(rotation));
  glUniform3fv(program.uniform("u_translation_cam_from_world"), 1, glm::value_ptr(translation));
  glUniform3fv(program.uniform("u_eye_w"), 1, glm::value_ptr(eye_w));
  glUniform4f(program.uniform("u_distortion"), static_cast<float>(camera.distortion[0]),
              static_cast<float>(camera.distortion[1]), static_cast<float>(camera.distortion[2]),
              static_cast<float>(camera.distortion[3]));
  glUniform1f(program.uniform("u_distortion_k3"), static_cast<float>(camera.distortion[4]));
  glUniform2f(program.uniform("u_focal_px"), static_cast<float>(camera.fx_px), static_cast<float>(camera.fy_px));
  glUniform2f(program.uniform("u_principal_px"), static_cast<float>(camera.cx_px), static_cast<float>(camera.cy_px));
  glUniform2f(program.uniform("u_image_size_px"), static_cast<float>(camera.width_px),
              static_cast<float>(camera.height_px));
  glUniform2f(program.uniform("u_depth_range_m"), static_cast<float>(near_m), static_cast<float>(far_m));
}

void bindCubeMapUniforms(const gles::Program& program, const std::string& prefix, const GpuCubeMap& map, int unit) {
  glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(unit));
  glBindTexture(GL_TEXTURE_CUBE_MAP, map.texture.id());
  glUniform1i(program.uniform((prefix + "_map").c_str()), unit);
  glUniform1f(program.uniform((prefix + "_face_size").c_str()), static_cast<float>(map.face_size));
  glUniform1f(program.uniform((prefix + "_scale").c_str()), map.linear_scale);
}

}  // namespace probelight::passes
