#include "passes/virtual_lamp_light.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

#include <glm/gtc/type_ptr.hpp>

#include "ibl/camera_projection.hpp"
#include "passes/camera_response.hpp"
#include "passes/framebuffer_state_guard.hpp"
#include "passes/layer_target.hpp"

namespace probelight::passes {

glm::vec4 rigWindowRect(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const RigGeometry& rig) {
  const glm::vec4 everywhere(-1e6f, -1e6f, 1e6f, 1e6f);
  // The box around the ball and its post, down to the ground.
  const glm::dvec3 c = rig.probe_center_w;
  const double r = rig.probe_radius_m;
  glm::dvec2 low(1e300), high(-1e300);
  for (int k = 0; k < 8; ++k) {
    const glm::dvec3 corner(c.x + ((k & 1) ? r : -r), c.y + ((k & 2) ? r : -r), (k & 4) ? c.z + r : 0.0);
    const glm::dvec3 in_camera = pose.toCamera(corner);
    if (!(in_camera.z > 1e-3)) return everywhere;
    const glm::dvec2 pixel = ibl::projectToPixel(camera, in_camera);
    if (!std::isfinite(pixel.x) || !std::isfinite(pixel.y)) return everywhere;
    low = glm::min(low, pixel);
    high = glm::max(high, pixel);
  }
  // Window coordinates (gl_FragCoord: pixel centres at +0.5, rows from
  // the bottom), 2 px of margin for the lens's bow between corners.
  constexpr double kMarginPx = 2.0;
  return glm::vec4(static_cast<float>(low.x + 0.5 - kMarginPx),
                   static_cast<float>(camera.height_px - (high.y + 0.5) - kMarginPx),
                   static_cast<float>(high.x + 0.5 + kMarginPx),
                   static_cast<float>(camera.height_px - (low.y + 0.5) + kMarginPx));
}

bool VirtualLampLight::init(const gles::Capabilities& capabilities, const VirtualLampLightSettings& settings,
                            const CameraIntrinsics& camera, std::string& error) {
  settings_ = settings;
  if (settings.shadow_mask_size_px < 16 || settings.shadow_mask_size_px > capabilities.max_texture_size_px ||
      settings.grid_columns < 1 || settings.grid_columns > 200) {
    error = "virtual lamp: shadow_mask_size_px must be 16.." + std::to_string(capabilities.max_texture_size_px) +
            " and grid_columns 1..200";
    return false;
  }
  auto shadow = gles::Program::fromEmbedded("virtual_lamp_shadow.vert", "virtual_lamp_shadow.frag", "", error);
  if (!shadow) return false;
  auto light = gles::Program::fromEmbedded("virtual_lamp.vert", "virtual_lamp.frag",
                                           cameraTransferDefines(settings.camera_transfer), error);
  if (!light) return false;
  auto point = gles::Program::fromEmbedded("virtual_lamp.vert", "virtual_lamp.frag",
                                           "#define LAMP_POINT\n" + cameraTransferDefines(settings.camera_transfer),
                                           error);
  if (!point) return false;
  point_program_ = std::move(*point);
  auto detail = gles::Program::fromEmbedded("virtual_lamp.vert", "virtual_lamp.frag",
                                            "#define LAMP_DETAIL\n" + cameraTransferDefines(settings.camera_transfer),
                                            error);
  if (!detail) return false;
  shadow_program_ = std::move(*shadow);
  light_program_ = std::move(*light);
  detail_program_ = std::move(*detail);
  const int size = settings.shadow_mask_size_px;
  if (!makeColourLayer(size, size, nullptr, "the virtual lamp's shadow mask", shadow_mask_, shadow_framebuffer_, error))
    return false;
  // The frame's grid: at each vertex, its place in NDC and the camera's
  // undistorted ray through that pixel (the frame's edges are the pixels'
  // outer edges, half a pixel past the first and last centres).
  const int columns = settings.grid_columns;
  const int rows = std::max(1, static_cast<int>(std::lround(columns * static_cast<double>(camera.height_px) /
                                                             std::max(camera.width_px, 1))));
  std::vector<float> vertices;
  for (int j = 0; j <= rows; ++j)
    for (int i = 0; i <= columns; ++i) {
      const double x = -0.5 + camera.width_px * static_cast<double>(i) / columns;
      const double y = -0.5 + camera.height_px * static_cast<double>(j) / rows;
      const glm::dvec3 ray = ibl::pixelToCameraRay(camera, {x, y});
      vertices.insert(vertices.end(), {static_cast<float>(2.0 * (x + 0.5) / camera.width_px - 1.0),
                                       static_cast<float>(1.0 - 2.0 * (y + 0.5) / camera.height_px),
                                       static_cast<float>(ray.x), static_cast<float>(ray.y), static_cast<float>(ray.z)});
    }
  std::vector<GLushort> indices;
  const auto at = [&](int a, int b) { return static_cast<GLushort>(b * (columns + 1) + a); };
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i)
      indices.insert(indices.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)});
  if ((columns + 1) * (rows + 1) > 65536) {
    error = "virtual lamp: the grid needs over 65536 vertices";
    return false;
  }
  grid_index_count_ = static_cast<GLsizei>(indices.size());
  grid_vertices_ = gles::Buffer::create();
  glBindBuffer(GL_ARRAY_BUFFER, grid_vertices_.id());
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)), vertices.data(),
               GL_STATIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  grid_indices_ = gles::Buffer::create();
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, grid_indices_.id());
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(GLushort)), indices.data(),
               GL_STATIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  caster_vertices_ = gles::Buffer::create();
  return gles::checkGl("VirtualLampLight::init", error);
}

bool VirtualLampLight::updateShadow(const ibl::VirtualLamp& lamp, const std::vector<glm::vec3>& caster_triangles_w,
                                    std::string& error) {
  lamp_ = lamp;
  // The planar projection flattens what is below the lamp; a vertex at or
  // above it would land behind it, on the wrong side.
  float highest_m = 0.0f;
  for (const glm::vec3& v : caster_triangles_w) highest_m = std::max(highest_m, v.z);
  casts_shadow_ = !caster_triangles_w.empty() && static_cast<double>(highest_m) < lamp.position_w.z - 1e-3;
  mask_square_ = ibl::GroundRegion{};
  if (casts_shadow_) {
    // The shadow's extent: every vertex flattened from the lamp.
    const glm::dmat4 flatten = ibl::groundShadowProjection(lamp.position_w);
    glm::dvec2 low(1e300), high(-1e300);
    for (const glm::vec3& v : caster_triangles_w) {
      const glm::dvec4 h = flatten * glm::dvec4(glm::dvec3(v), 1.0);
      const glm::dvec2 at(h.x / h.w, h.y / h.w);
      low = glm::min(low, at);
      high = glm::max(high, at);
    }
    // Two texels of margin, for the bilinear read at the shadow's edge.
    const double half = 0.5 * std::max(high.x - low.x, high.y - low.y);
    mask_square_.centre_w = 0.5 * (low + high);
    mask_square_.half_size_m = half * (1.0 + 4.0 / settings_.shadow_mask_size_px) + 1e-4;
  }
  DrawTargetState saved;
  saved.capture();
  glBindFramebuffer(GL_FRAMEBUFFER, shadow_framebuffer_.id());
  glViewport(0, 0, settings_.shadow_mask_size_px, settings_.shadow_mask_size_px);
  glDisable(GL_SCISSOR_TEST);
  glClearColor(1.0f, 1.0f, 1.0f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  if (casts_shadow_) {
    if (caster_triangles_w.data() != uploaded_data_ || caster_triangles_w.size() != uploaded_size_) {
      glBindBuffer(GL_ARRAY_BUFFER, caster_vertices_.id());
      glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(caster_triangles_w.size() * sizeof(glm::vec3)),
                   caster_triangles_w.data(), GL_STATIC_DRAW);
      uploaded_data_ = caster_triangles_w.data();
      uploaded_size_ = caster_triangles_w.size();
    }
    // The mask's square as NDC: ((x / w) - centre) / half, written in
    // homogeneous form so that the flattening's divide is GL's.
    const double half = mask_square_.half_size_m;
    glm::dmat4 square(0.0);
    square[0][0] = 1.0 / half;
    square[3][0] = -mask_square_.centre_w.x / half;
    square[1][1] = 1.0 / half;
    square[3][1] = -mask_square_.centre_w.y / half;
    square[3][3] = 1.0;
    const glm::mat4 clip_from_world(square * ibl::groundShadowProjection(lamp.position_w));
    shadow_program_.use();
    glUniformMatrix4fv(shadow_program_.uniform("u_clip_from_world"), 1, GL_FALSE, glm::value_ptr(clip_from_world));
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    const GLint position = shadow_program_.attribute("a_position_w");
    glBindBuffer(GL_ARRAY_BUFFER, caster_vertices_.id());
    glEnableVertexAttribArray(static_cast<GLuint>(position));
    glVertexAttribPointer(static_cast<GLuint>(position), 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(caster_triangles_w.size()));
    glDisableVertexAttribArray(static_cast<GLuint>(position));
    glBindBuffer(GL_ARRAY_BUFFER, 0);
  }
  saved.restore();
  return gles::checkGl("VirtualLampLight::updateShadow", error);
}

bool VirtualLampLight::drawPass(bool detail, const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                                const CameraFrameTexture& camera_frame, const RigGeometry& rig, const Frame& frame,
                                std::string& error) {
  const gles::Program& p = detail                                ? detail_program_
                           : lamp_.spot_half_angle_deg >= 180.0 ? point_program_
                                                                 : light_program_;
  p.use();
  const glm::mat3 world_from_cam(glm::transpose(pose.R_cam_from_world));
  glUniformMatrix3fv(p.uniform("u_world_from_cam"), 1, GL_FALSE, glm::value_ptr(world_from_cam));
  const glm::vec3 eye(pose.cameraCenterWorld());
  glUniform3fv(p.uniform("u_eye_w"), 1, glm::value_ptr(eye));
  const glm::vec3 lamp_at(lamp_.position_w), ratio_1m(frame.ratio_at_one_metre_rgb);
  // virtual_lamp.glsl's lamp.
  glUniform3fv(p.uniform("u_lamp_w"), 1, glm::value_ptr(lamp_at));
  glUniform3fv(p.uniform("u_lamp_ratio_at_one_metre"), 1, glm::value_ptr(ratio_1m));
  const glm::vec3 spot_direction(glm::normalize(lamp_.spot_direction_w));
  glUniform3fv(p.uniform("u_spot_direction_w"), 1, glm::value_ptr(spot_direction));
  const ibl::SpotCosines cosines = ibl::spotCosines(lamp_);
  glUniform2f(p.uniform("u_spot_cosines"), static_cast<float>(cosines.outer), static_cast<float>(cosines.inner));
  glUniform1f(p.uniform("u_spot"), lamp_.spot_half_angle_deg < 180.0 ? 1.0f : 0.0f);
  glUniform2f(p.uniform("u_image_size_px"), static_cast<float>(camera.width_px), static_cast<float>(camera.height_px));
  if (settings_.camera_transfer.curve == ibl::CameraTransfer::Curve::kGamma)
    glUniform1f(p.uniform("u_camera_gamma"), static_cast<float>(settings_.camera_transfer.gamma));
  glUniform1f(p.uniform("u_exposure_gain"), static_cast<float>(frame.exposure_gain));
  const bool dome = frame.dome_shadow != nullptr && frame.dome_shadow->hasShadow();
  const glm::vec4 rig_rect = rigWindowRect(camera, pose, rig);
  GLint viewport[4] = {0, 0, 0, 0};
  glGetIntegerv(GL_VIEWPORT, viewport);
  const GLboolean scissor_was = glIsEnabled(GL_SCISSOR_TEST);
  GLint saved_box[4] = {0, 0, 0, 0};
  glGetIntegerv(GL_SCISSOR_BOX, saved_box);
  const ibl::GroundRegion dome_region = dome ? frame.dome_shadow->region() : ibl::GroundRegion{};
  glUniform2f(p.uniform("u_dome_centre_w"), static_cast<float>(dome_region.centre_w.x),
              static_cast<float>(dome_region.centre_w.y));
  glUniform1f(p.uniform("u_dome_half_size_m"), dome ? static_cast<float>(dome_region.half_size_m) : 0.0f);
  if (detail) {
    glUniform2f(p.uniform("u_mask_centre_w"), static_cast<float>(mask_square_.centre_w.x),
                static_cast<float>(mask_square_.centre_w.y));
    glUniform1f(p.uniform("u_mask_half_size_m"), casts_shadow_ ? static_cast<float>(mask_square_.half_size_m) : 0.0f);
    glUniform4f(p.uniform("u_ball_w"), static_cast<float>(rig.probe_center_w.x), static_cast<float>(rig.probe_center_w.y),
                static_cast<float>(rig.probe_center_w.z), static_cast<float>(rig.probe_radius_m));
    glUniform3f(p.uniform("u_post_w"), static_cast<float>(rig.probe_center_w.x), static_cast<float>(rig.probe_center_w.y),
                static_cast<float>(rig.post_radius_m));
    glUniform4fv(p.uniform("u_rig_rect_px"), 1, glm::value_ptr(rig_rect));
    // Cut to the frame's rectangle about the object's shadow from the lamp
    // and the rig (the whole frame when a corner is behind the camera).
    glm::dvec2 low(rig_rect.x - 0.5, camera.height_px - rig_rect.w - 0.5);
    glm::dvec2 high(rig_rect.z - 0.5, camera.height_px - rig_rect.y - 0.5);
    bool everywhere = rig_rect.x < -1e5f;
    if (casts_shadow_)
      for (int k = 0; k < 4; ++k) {
        const glm::dvec3 corner(mask_square_.centre_w +
                                    mask_square_.half_size_m * glm::dvec2((k & 1) ? 1.0 : -1.0, (k & 2) ? 1.0 : -1.0),
                                0.0);
        const glm::dvec3 in_camera = pose.toCamera(corner);
        const glm::dvec2 pixel = ibl::projectToPixel(camera, in_camera);
        if (!(in_camera.z > 1e-3) || !std::isfinite(pixel.x) || !std::isfinite(pixel.y)) {
          everywhere = true;
          continue;
        }
        low = glm::min(low, pixel);
        high = glm::max(high, pixel);
      }
    if (!everywhere) {
      // Whole pixels, 2 px of margin for the lens's bow between corners.
      const int x0 = std::clamp(static_cast<int>(std::floor(low.x)) - 2, 0, camera.width_px);
      const int x1 = std::clamp(static_cast<int>(std::ceil(high.x)) + 3, 0, camera.width_px);
      const int y0 = std::clamp(static_cast<int>(std::floor(low.y)) - 2, 0, camera.height_px);
      const int y1 = std::clamp(static_cast<int>(std::ceil(high.y)) + 3, 0, camera.height_px);
      glEnable(GL_SCISSOR_TEST);
      glScissor(viewport[0] + x0, viewport[1] + camera.height_px - y1, std::max(0, x1 - x0), std::max(0, y1 - y0));
    }
  }
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, camera_frame.texture());
  // Read 1:1 at texel centres: NEAREST is the same texel as LINEAR, at
  // about half llvmpipe's cost (as the background's draw does).
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glUniform1i(p.uniform("u_camera"), 0);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, shadow_mask_.id());
  glUniform1i(p.uniform("u_lamp_shadow"), 1);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_2D, dome ? frame.dome_shadow->fractionTexture() : shadow_mask_.id());
  glUniform1i(p.uniform("u_dome_shadow"), 2);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glBindBuffer(GL_ARRAY_BUFFER, grid_vertices_.id());
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, grid_indices_.id());
  const GLint ndc = p.attribute("a_ndc"), ray = p.attribute("a_ray_cam");
  constexpr GLsizei kStride = 5 * sizeof(float);
  // A compiler may drop the ray where no pixel reads it (-1).
  for (const auto& [location, size, offset] : {std::tuple{ndc, 2, 0}, std::tuple{ray, 3, 2}}) {
    if (location < 0) continue;
    glEnableVertexAttribArray(static_cast<GLuint>(location));
    glVertexAttribPointer(static_cast<GLuint>(location), size, GL_FLOAT, GL_FALSE, kStride,
                          reinterpret_cast<const void*>(offset * sizeof(float)));
  }
  glDrawElements(GL_TRIANGLES, grid_index_count_, GL_UNSIGNED_SHORT, nullptr);
  for (GLint location : {ndc, ray})
    if (location >= 0) glDisableVertexAttribArray(static_cast<GLuint>(location));
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  if (scissor_was) {
    glScissor(saved_box[0], saved_box[1], saved_box[2], saved_box[3]);
  } else {
    glDisable(GL_SCISSOR_TEST);
  }
  glActiveTexture(GL_TEXTURE0);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  for (GLenum unit : {GL_TEXTURE2, GL_TEXTURE1, GL_TEXTURE0}) {
    glActiveTexture(unit);
    glBindTexture(GL_TEXTURE_2D, 0);
  }
  return gles::checkGl(detail ? "VirtualLampLight::drawDetail" : "VirtualLampLight::drawSmooth", error);
}

}  // namespace probelight::passes
