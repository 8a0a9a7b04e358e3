#include "passes/object_compositor.hpp"

#include "passes/object_uniforms.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include <glm/gtc/constants.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace probelight::passes {

namespace {
// The bound 2D texture's minification and magnification filter.
void setTextureFilter(GLint filter) {
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
}
}  // namespace

int sphereSegmentsFor(double radius_px, double max_sag_px) {
  for (int segments : kSphereSegmentSteps)
    if (radius_px * (1.0 - std::cos(glm::pi<double>() / segments)) <= max_sag_px) return segments;
  return kSphereSegmentSteps[std::size(kSphereSegmentSteps) - 1];
}

double sphereSilhouetteRadiusBoundPx(double focal_px, double radius_m, double depth_m) {
  if (!(depth_m > radius_m)) return std::numeric_limits<double>::infinity();
  return focal_px * radius_m / (depth_m - radius_m);
}

ReflectionRungs reflectionRungsFor(float glossiness, int glossy_levels) {
  const int levels = std::clamp(glossy_levels, 0, 2);
  // Rung k of the ladder: 0 the mirror, 1..L the glossy maps, L + 1 the diffuse map.
  auto kindOf = [levels](int rung) { return rung == 0 ? 0 : rung <= levels ? rung : 3; };
  const ibl::ReflectionLadderBlend blend = ibl::reflectionLadderBlend(glossiness, levels);
  ReflectionRungs rungs;
  rungs.lower_kind = kindOf(blend.lower);
  if (blend.toward_next > 0.0f) {
    rungs.upper_kind = kindOf(blend.lower + 1);
    rungs.toward_upper = blend.toward_next;
  }
  return rungs;
}

bool ObjectCompositor::init(const gles::Capabilities& /*capabilities*/, const ObjectCompositorSettings& settings,
                            CubeStorage storage, std::string& error) {
  settings_ = settings;
  storage_ = storage;
  if (!(settings.max_silhouette_sag_px > 0.0)) {
    error = "ObjectCompositor: max_silhouette_sag_px must be > 0";
    return false;
  }
  if (!(settings.near_m > 0.0 && settings.far_m > settings.near_m)) {
    error = "ObjectCompositor: depth range needs 0 < near_m < far_m";
    return false;
  }
  if (!quad_.init(error)) return false;
  auto image_program = gles::Program::fromEmbedded("image_quad.vert", "image_quad.frag", "", error);
  if (!image_program) return false;
  image_program_ = std::move(*image_program);
  auto darkened = gles::Program::fromEmbedded("image_quad.vert", "image_quad.frag",
                                              "#define EXPOSURE_GAIN\n" + cameraTransferDefines(settings.camera_transfer),
                                              error);
  if (!darkened) return false;
  darkened_image_program_ = std::move(*darkened);
  // The mirror-only programs (glossiness 1, the default) now, so a shader
  // that does not build fails init; other rungs' programs on first use.
  shading_programs_.clear();
  if (!shadingProgram(ObjectShape::kSphere, ReflectionRungs{}, false, false, error) ||
      !shadingProgram(ObjectShape::kMesh, ReflectionRungs{}, false, false, error))
    return false;

  sphere_meshes_.clear();
  for (int segments : kSphereSegmentSteps) {
    // Unit sphere, latitude rings from the south pole to the north pole.
    const int columns = segments;
    const int rows = segments / 2;
    std::vector<GLfloat> vertices;
    vertices.reserve(static_cast<size_t>((columns + 1) * (rows + 1) * 3));
    for (int row = 0; row <= rows; ++row) {
      const double polar = glm::pi<double>() * row / rows;
      for (int column = 0; column <= columns; ++column) {
        const double azimuth = 2.0 * glm::pi<double>() * column / columns;
        vertices.push_back(static_cast<GLfloat>(std::sin(polar) * std::cos(azimuth)));
        vertices.push_back(static_cast<GLfloat>(std::sin(polar) * std::sin(azimuth)));
        vertices.push_back(static_cast<GLfloat>(-std::cos(polar)));
      }
    }
    // GLES2 core has only 16-bit indices (the largest step has 8,385 vertices).
    std::vector<GLushort> indices;
    for (int row = 0; row < rows; ++row) {
      for (int column = 0; column < columns; ++column) {
        const auto a = static_cast<GLushort>(row * (columns + 1) + column);
        const auto b = static_cast<GLushort>(a + 1);
        const auto c = static_cast<GLushort>(a + columns + 1);
        const auto d = static_cast<GLushort>(c + 1);
        indices.insert(indices.end(), {a, b, d, a, d, c});  // counter-clockwise seen from outside
      }
    }
    SphereMesh mesh;
    mesh.segments = segments;
    mesh.index_count = static_cast<GLsizei>(indices.size());
    mesh.vertices = gles::Buffer::create();
    glBindBuffer(GL_ARRAY_BUFFER, mesh.vertices.id());
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(GLfloat)), vertices.data(),
                 GL_STATIC_DRAW);
    mesh.indices = gles::Buffer::create();
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, mesh.indices.id());
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(GLushort)),
                 indices.data(), GL_STATIC_DRAW);
    sphere_meshes_.push_back(std::move(mesh));
  }
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  overlay_ = gles::Texture();
  return gles::checkGl("ObjectCompositor::init", error);
}

const gles::Program* ObjectCompositor::shadingProgram(ObjectShape shape, const ReflectionRungs& rungs,
                                                     bool match_noise, bool bloom_bright_pass, std::string& error) {
  match_noise = match_noise && !bloom_bright_pass;
  const auto key = std::make_tuple(shape, rungs.lower_kind, rungs.upper_kind, match_noise, bloom_bright_pass);
  if (auto found = shading_programs_.find(key); found != shading_programs_.end()) return &found->second;
  std::string defines = cubeStorageDefines(storage_) + cameraResponseDefines(settings_.camera_transfer, match_noise) +
                        (bloom_bright_pass ? bloomBrightPassDefines() : std::string()) +
                        "#define REFLECTION_LOWER_RUNG " + std::to_string(rungs.lower_kind) + "\n";
  if (rungs.upper_kind >= 0) defines += "#define REFLECTION_UPPER_RUNG " + std::to_string(rungs.upper_kind) + "\n";
  auto program = gles::Program::fromEmbedded(shape == ObjectShape::kSphere ? "sphere_object.vert" : "mesh_object.vert",
                                             "sphere_object.frag", defines, error);
  if (!program) return nullptr;
  return &shading_programs_.emplace(key, std::move(*program)).first->second;
}

void ObjectCompositor::clearDepth() {
  glDepthMask(GL_TRUE);
  glClear(GL_DEPTH_BUFFER_BIT);
}

void ObjectCompositor::drawCameraBackground(const CameraFrameTexture& camera_frame, double exposure_gain) {
  clearDepth();
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  // The bytes as they are, or through linear light when darkened.
  const gles::Program& program = exposure_gain == 1.0 ? image_program_ : darkened_image_program_;
  program.use();
  if (exposure_gain != 1.0) {
    glUniform1f(program.uniform("u_exposure_gain"), static_cast<float>(exposure_gain));
    if (settings_.camera_transfer.curve == ibl::CameraTransfer::Curve::kGamma)
      glUniform1f(program.uniform("u_camera_gamma"), static_cast<float>(settings_.camera_transfer.gamma));
  }
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, camera_frame.texture());
  // Drawn 1:1, every lookup at a texel centre: NEAREST gives the same
  // texels as LINEAR and is half the cost on llvmpipe (1.0 vs 2.2 ms at
  // 640x480). The texture's own filter stays LINEAR for the reflection
  // map's lookups, which fall between texels.
  setTextureFilter(GL_NEAREST);
  glUniform1i(program.uniform("u_image"), 0);
  quad_.draw(program.attribute("a_position"));
  setTextureFilter(GL_LINEAR);
}

const gles::Program* ObjectCompositor::prepareShading(ObjectShape shape, const CameraIntrinsics& camera,
                                                     const PoseCamFromWorld& pose, const ibl::SurfaceMaterial& material,
                                                     const ibl::SceneLighting& lighting, EnvironmentMaps& environment,
                                                     std::string& error) {
  if (environment.storage() != storage_) {
    error = "ObjectCompositor: initialised for a different cube map storage than these EnvironmentMaps use";
    return nullptr;
  }
  // Glossy levels only when updateGlossy has made them; otherwise the ladder
  // is mirror -> diffuse.
  const int glossy_levels = environment.glossyWritten() ? environment.glossyLevels() : 0;
  const ReflectionRungs rungs = reflectionRungsFor(material.glossiness, glossy_levels);
  if (sensor_noise_ != nullptr && !noise_texture_.valid() && !noise_texture_.init(error)) return nullptr;
  const gles::Program* shading = shadingProgram(shape, rungs, sensor_noise_ != nullptr, bloom_bright_pass_, error);
  if (shading == nullptr) return nullptr;
  const gles::Program& program = *shading;
  const GpuCubeMap& diffuse = environment.diffuse();
  const GpuCubeMap& reflection = environment.reflection();
  program.use();
  setCameraProjectionUniforms(program, camera, pose, settings_.near_m, settings_.far_m);
  bindCubeMapUniforms(program, "u_diffuse", diffuse, 0);
  bindCubeMapUniforms(program, "u_reflection", reflection, 1);
  // Absent glossy levels' samplers get the diffuse map (a complete cube
  // map; the shader never reads them).
  for (int level = 0; level < 2; ++level)
    bindCubeMapUniforms(program, "u_glossy" + std::to_string(level),
                        level < glossy_levels ? environment.glossy(level) : diffuse, 2 + level);
  glUniform1f(program.uniform("u_toward_upper_rung"), rungs.toward_upper);
  setCameraResponseUniforms(program, settings_.camera_transfer, response_gain_rgb_,
                            bloom_bright_pass_ ? nullptr : sensor_noise_, noise_texture_, 4);
  glActiveTexture(GL_TEXTURE0);

  glUniform3fv(program.uniform("u_albedo"), 1, glm::value_ptr(material.albedo));
  glUniform1f(program.uniform("u_material_ambient"), material.ambient);
  glUniform1f(program.uniform("u_k_diffuse"), material.k_diffuse);
  glUniform1f(program.uniform("u_k_specular"), material.k_specular);
  glUniform1f(program.uniform("u_shininess"), material.shininess);
  glUniform1f(program.uniform("u_k_reflect"), material.k_reflect);
  glUniform3fv(program.uniform("u_ambient_rgb"), 1, glm::value_ptr(lighting.ambient_rgb));
  const glm::vec3 highlight_direction = glm::normalize(lighting.highlight_direction_w);
  glUniform3fv(program.uniform("u_highlight_direction_w"), 1, glm::value_ptr(highlight_direction));
  glUniform3fv(program.uniform("u_highlight_rgb"), 1, glm::value_ptr(lighting.highlight_rgb));
  glUniform3fv(program.uniform("u_clipped_direction_w"), ibl::SceneLighting::kMaxClippedLights,
               glm::value_ptr(lighting.clipped_direction_w[0]));
  glUniform3fv(program.uniform("u_clipped_diffuse_rgb"), ibl::SceneLighting::kMaxClippedLights,
               glm::value_ptr(lighting.clipped_diffuse_rgb[0]));
  glUniform3fv(program.uniform("u_lamp_direction_w"), 1, glm::value_ptr(lighting.lamp_direction_w));
  glUniform3fv(program.uniform("u_lamp_diffuse_rgb"), 1, glm::value_ptr(lighting.lamp_diffuse_rgb));

  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
  // Back faces culled: half the fragments of a closed object, which the depth
  // test would otherwise shade and then overwrite (or reject) after the
  // fact. Triangles are counter-clockwise seen from outside (the sphere's
  // rings and boxMesh's faces); the camera frame (x right, y down, z ahead)
  // is right-handed and its y is flipped into NDC, so a face toward the
  // camera is counter-clockwise in window coordinates too: GL's default
  // front face.
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CCW);
  return shading;
}

bool ObjectCompositor::drawSphereObject(const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                                        glm::dvec3 centre_w, double radius_m, const ibl::SurfaceMaterial& material,
                                        const ibl::SceneLighting& lighting, EnvironmentMaps& environment,
                                        std::string& error) {
  const gles::Program* shading = prepareShading(ObjectShape::kSphere, camera, pose, material, lighting, environment, error);
  if (shading == nullptr) return false;
  const gles::Program& program = *shading;
  glUniform3f(program.uniform("u_center_w"), static_cast<float>(centre_w.x), static_cast<float>(centre_w.y),
              static_cast<float>(centre_w.z));
  glUniform1f(program.uniform("u_radius_m"), static_cast<float>(radius_m));
  const GLint unit = program.attribute("a_unit");
  if (unit < 0) {
    error = "ObjectCompositor: sphere_object.vert has no attribute a_unit";
    return false;
  }
  const double depth_m = pose.toCamera(centre_w).z;
  const int segments = sphereSegmentsFor(
      sphereSilhouetteRadiusBoundPx(std::max(camera.fx_px, camera.fy_px), radius_m, depth_m),
      settings_.max_silhouette_sag_px);
  const SphereMesh* mesh = &sphere_meshes_.back();
  for (const SphereMesh& candidate : sphere_meshes_)
    if (candidate.segments == segments) mesh = &candidate;
  glBindBuffer(GL_ARRAY_BUFFER, mesh->vertices.id());
  glEnableVertexAttribArray(static_cast<GLuint>(unit));
  glVertexAttribPointer(static_cast<GLuint>(unit), 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, mesh->indices.id());
  glDrawElements(GL_TRIANGLES, mesh->index_count, GL_UNSIGNED_SHORT, nullptr);
  glDisableVertexAttribArray(static_cast<GLuint>(unit));
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  return gles::checkGl("ObjectCompositor::drawSphereObject", error);
}

bool ObjectCompositor::drawMeshObject(const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                                      const std::vector<MeshVertex>& triangles, const ibl::SurfaceMaterial& material,
                                      const ibl::SceneLighting& lighting, EnvironmentMaps& environment,
                                      std::string& error) {
  if (triangles.empty()) return true;
  const gles::Program* shading = prepareShading(ObjectShape::kMesh, camera, pose, material, lighting, environment, error);
  if (shading == nullptr) return false;
  const gles::Program& program = *shading;
  if (!mesh_vertices_.valid()) mesh_vertices_ = gles::Buffer::create();
  glBindBuffer(GL_ARRAY_BUFFER, mesh_vertices_.id());
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(triangles.size() * sizeof(MeshVertex)), triangles.data(),
               GL_DYNAMIC_DRAW);
  const GLint position = program.attribute("a_position_w"), normal = program.attribute("a_normal_w");
  if (position < 0 || normal < 0) {
    error = "ObjectCompositor: mesh_object.vert lacks a_position_w or a_normal_w";
    return false;
  }
  glEnableVertexAttribArray(static_cast<GLuint>(position));
  glVertexAttribPointer(static_cast<GLuint>(position), 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex), nullptr);
  glEnableVertexAttribArray(static_cast<GLuint>(normal));
  glVertexAttribPointer(static_cast<GLuint>(normal), 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                        reinterpret_cast<const void*>(sizeof(glm::vec3)));
  glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(triangles.size()));
  glDisableVertexAttribArray(static_cast<GLuint>(position));
  glDisableVertexAttribArray(static_cast<GLuint>(normal));
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  return gles::checkGl("ObjectCompositor::drawMeshObject", error);
}

bool ObjectCompositor::drawOverlayRGBA(const std::uint8_t* rgba, int width, int height, std::string& error) {
  if (rgba == nullptr || width <= 0 || height <= 0) {
    error = "ObjectCompositor::drawOverlayRGBA: empty overlay";
    return false;
  }
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  if (!overlay_.valid() || width != overlay_width_ || height != overlay_height_) {
    auto texture = gles::createTexture2D(width, height, GL_RGBA, GL_UNSIGNED_BYTE, GL_LINEAR, rgba, error);
    if (!texture) return false;
    overlay_ = std::move(*texture);
    overlay_width_ = width;
    overlay_height_ = height;
  } else {
    glBindTexture(GL_TEXTURE_2D, overlay_.id());
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
  }
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  image_program_.use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, overlay_.id());
  glUniform1i(image_program_.uniform("u_image"), 0);
  quad_.draw(image_program_.attribute("a_position"));
  glDisable(GL_BLEND);
  return gles::checkGl("ObjectCompositor::drawOverlayRGBA", error);
}

std::vector<ObjectCompositor::MeshVertex> boxMesh(const ibl::ShadowCaster& box) {
  const double c = std::cos(box.box_yaw_rad), s = std::sin(box.box_yaw_rad);
  const glm::dvec3 centre = box.boundingCentre();
  auto toWorld = [&](const glm::dvec3& local) { return glm::dvec3(c * local.x - s * local.y, s * local.x + c * local.y, local.z); };
  std::vector<ObjectCompositor::MeshVertex> triangles;
  // Each face: its outward axis n and two in-face axes a, b with a x b = n.
  const glm::dvec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int axis = 0; axis < 3; ++axis)
    for (double sign : {1.0, -1.0}) {
      const glm::dvec3 n = sign * axes[axis];
      const glm::dvec3 a = axes[(axis + 1) % 3], b = glm::cross(n, a);
      const glm::dvec3 half = 0.5 * box.box_size_m;
      auto corner = [&](double u, double v) {
        const glm::dvec3 local = n * half + u * a * half + v * b * half;
        return glm::vec3(centre + toWorld(local));
      };
      const glm::vec3 normal(toWorld(n));
      const glm::vec3 p00 = corner(-1, -1), p10 = corner(1, -1), p11 = corner(1, 1), p01 = corner(-1, 1);
      for (const glm::vec3& p : {p00, p10, p11, p00, p11, p01}) triangles.push_back({p, normal});
    }
  return triangles;
}

}  // namespace probelight::passes
