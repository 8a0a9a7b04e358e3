#include "passes/ground_shadow.hpp"
#include "core/math_constants.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/type_ptr.hpp>

namespace probelight::passes {

namespace {

// How much bigger than the object's bounding sphere the light's frustum is:
// PCF taps near the silhouette stay inside the map.
constexpr double kFrustumMargin = 1.04;
// Depth comparison bias, in [0, 1] units of the frustum's depth (twice the
// bounding radius): two 10-bit mediump steps. Ground points that close to
// the object's far side (where it stands on the ground) count as hidden;
// the ground never shadows itself, so there is no acne to fight.

}  // namespace

std::array<glm::vec2, kShadowTaps> shadowDiscTaps() {
  std::array<glm::vec2, kShadowTaps> taps{};
  for (int k = 0; k < kShadowTaps; ++k) {
    // Golden-angle spiral: even cover of the unit disc by equal areas.
    const double r = std::sqrt((k + 0.5) / kShadowTaps), phi = k * kPi * (3.0 - std::sqrt(5.0));
    taps[static_cast<size_t>(k)] = glm::vec2(static_cast<float>(r * std::cos(phi)), static_cast<float>(r * std::sin(phi)));
  }
  return taps;
}

LightView lightViewFor(const glm::dvec3& direction_w, const glm::dvec3& centre_w, double radius_m) {
  const glm::dvec3 d = glm::normalize(direction_w);
  const glm::dvec3 helper = std::abs(d.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0);
  const glm::dvec3 right = glm::normalize(glm::cross(helper, d));
  const glm::dvec3 up = glm::cross(d, right);
  const double half = kFrustumMargin * std::max(radius_m, 1e-6);
  LightView view;
  view.width_m = 2.0 * half;
  view.depth_m = 2.0 * half;
  // clip.x = right . (p - c) / half; clip.y = up . (p - c) / half;
  // depth01 = (half - d . (p - c)) / (2 half), clip.z = 2 depth01 - 1 = -d . (p - c) / half.
  glm::dmat4 m(0.0);
  for (int k = 0; k < 3; ++k) {
    m[k][0] = right[k] / half;
    m[k][1] = up[k] / half;
    m[k][2] = -d[k] / half;
  }
  m[3][0] = -glm::dot(right, centre_w) / half;
  m[3][1] = -glm::dot(up, centre_w) / half;
  m[3][2] = glm::dot(d, centre_w) / half;
  m[3][3] = 1.0;
  view.clip_from_world = m;
  // Ground points p(x, y) = c + x right + y up - t d with p.z = 0:
  // t = (c.z + x right.z + y up.z) / d.z; depth01 = (half + t') / (2 half)
  // grows with t, and uv with x / (2 half), so per uv the depth01 moves by
  // (right.z, up.z) / d.z. Lights at the horizon (d.z -> 0) are never
  // drawn (groundShadowLights keeps d.z > 0); the clamp keeps it finite.
  view.ground_depth_gradient_per_uv = glm::dvec2(right.z, up.z) / std::max(d.z, 1e-3);
  return view;
}

std::vector<glm::vec3> casterTriangles(const ibl::ShadowCaster& caster, int segments) {
  if (caster.shape == ibl::ShadowCaster::Shape::kMesh)
    return caster.mesh_triangles_w ? *caster.mesh_triangles_w : std::vector<glm::vec3>{};
  std::vector<glm::vec3> triangles;
  const glm::dvec3 centre = caster.boundingCentre();
  if (caster.shape == ibl::ShadowCaster::Shape::kSphere) {
    const int around = std::max(8, segments), rings = std::max(4, segments / 2);
    auto point = [&](int ring, int step) {
      const double theta = kPi * ring / rings, phi = 2.0 * kPi * step / around;
      return glm::vec3(centre + caster.radius_m * glm::dvec3(std::sin(theta) * std::cos(phi),
                                                             std::sin(theta) * std::sin(phi), std::cos(theta)));
    };
    for (int ring = 0; ring < rings; ++ring)
      for (int step = 0; step < around; ++step) {
        const glm::vec3 a = point(ring, step), b = point(ring + 1, step), c = point(ring + 1, step + 1),
                        d = point(ring, step + 1);
        triangles.insert(triangles.end(), {a, b, c, a, c, d});
      }
    return triangles;
  }
  const double c = std::cos(caster.box_yaw_rad), s = std::sin(caster.box_yaw_rad);
  auto corner = [&](int k) {
    const glm::dvec3 local(((k & 1) ? 0.5 : -0.5) * caster.box_size_m.x, ((k & 2) ? 0.5 : -0.5) * caster.box_size_m.y,
                           ((k & 4) ? 0.5 : -0.5) * caster.box_size_m.z);
    return glm::vec3(centre + glm::dvec3(c * local.x - s * local.y, s * local.x + c * local.y, local.z));
  };
  const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  // Each face's corners run clockwise seen from outside: the triangles
  // take them the other way, counter-clockwise like the sphere's.
  for (const auto& f : faces)
    triangles.insert(triangles.end(), {corner(f[0]), corner(f[2]), corner(f[1]), corner(f[0]), corner(f[3]), corner(f[2])});
  return triangles;
}

std::array<glm::dvec2, 4> shadowFootprintNdc(const LightView& view, double tan_cone, int map_size_px,
                                             const ibl::GroundRegion& region) {
  const std::array<glm::dvec2, 4> whole_square{glm::dvec2(-1, -1), glm::dvec2(1, -1), glm::dvec2(1, 1), glm::dvec2(-1, 1)};
  const glm::dmat4& m = view.clip_from_world;
  // On the ground, clip.xy = A p.xy + b and clip.z = g . p.xy + h.
  const glm::dmat2 a(m[0][0], m[0][1], m[1][0], m[1][1]);
  const glm::dvec2 b(m[3][0], m[3][1]);
  const double det = glm::determinant(a);
  if (!(std::abs(det) > 1e-12) || !(region.half_size_m > 0.0) || !(view.depth_m > 0.0) || !(view.width_m > 0.0))
    return whole_square;
  double receiver_max = 0.0;
  for (const glm::dvec2& corner : whole_square) {
    const glm::dvec2 p = region.centre_w + region.half_size_m * corner;
    receiver_max = std::max(receiver_max, 0.5 * (m[0][2] * p.x + m[1][2] * p.y + m[3][2]) + 0.5);
  }
  const double texel_uv = 1.0 / std::max(map_size_px, 1);
  const double reach_uv = 0.5 / kFrustumMargin + 0.71 * texel_uv + receiver_max * view.depth_m * std::max(tan_cone, 0.0) / view.width_m +
                          texel_uv;
  const double reach_clip = 2.0 * reach_uv;  // clip = 2 uv - 1
  const glm::dmat2 a_inverse = glm::inverse(a);
  std::array<glm::dvec2, 4> corners;
  const glm::dvec2 signs[4] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (int k = 0; k < 4; ++k) {
    const glm::dvec2 p = a_inverse * (reach_clip * signs[k] - b);
    corners[k] = (p - region.centre_w) / region.half_size_m;
    if (!(std::abs(corners[k].x) < 8.0 && std::abs(corners[k].y) < 8.0)) return whole_square;
  }
  return corners;
}

std::vector<bool> darkeningCells(const std::vector<glm::vec3>& fraction, int n, int segments) {
  std::vector<bool> cells(static_cast<std::size_t>(segments) * segments, false);
  if (n <= 0 || segments <= 0 || fraction.size() != static_cast<std::size_t>(n) * n) return cells;
  // The cell of texel column (or row) t: floor(t * segments / n).
  auto cellOf = [&](int t) { return std::clamp(t * segments / n, 0, segments - 1); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const glm::vec3& f = fraction[static_cast<std::size_t>(j) * n + i];
      if (!(std::min({f.r, f.g, f.b}) < 254.5f / 255.0f)) continue;
      // The texel and its neighbours: the cells they fall in.
      for (int cj = cellOf(std::max(0, j - 1)); cj <= cellOf(std::min(n - 1, j + 1)); ++cj)
        for (int ci = cellOf(std::max(0, i - 1)); ci <= cellOf(std::min(n - 1, i + 1)); ++ci)
          cells[static_cast<std::size_t>(cj) * segments + ci] = true;
    }
  return cells;
}

bool GroundShadow::init(const gles::Capabilities& capabilities, const GroundShadowSettings& settings,
                        std::string& error) {
  settings_ = settings;
  if (settings.shadow_map_size_px < 16 || settings.shadow_map_size_px > capabilities.max_texture_size_px ||
      settings.ground_texture_size_px < 16 || settings.ground_texture_size_px > capabilities.max_texture_size_px) {
    error = "ground shadow: map sizes must be 16.." + std::to_string(capabilities.max_texture_size_px) + " px";
    return false;
  }
  if (!(settings.max_region_half_size_m > 0.0) || settings.region_mesh_segments < 1) {
    error = "ground shadow: max_region_half_size_m must be > 0 and region_mesh_segments >= 1";
    return false;
  }
  packed_depth_ = settings.force_packed_depth || !capabilities.depth_texture;
  const std::string packed_define = packed_depth_ ? "#define SHADOW_DEPTH_PACKED\n" : "";
  auto depth = gles::Program::fromEmbedded("shadow_depth.vert", "shadow_depth.frag", packed_define, error);
  if (!depth) return false;
  auto ground = gles::Program::fromEmbedded("ground_shadow.vert", "ground_shadow.frag", packed_define, error);
  if (!ground) return false;
  std::string transfer_define;
  if (settings.camera_transfer.curve == ibl::CameraTransfer::Curve::kGamma) transfer_define = "#define CAMERA_TRANSFER_GAMMA\n";
  if (settings.camera_transfer.curve == ibl::CameraTransfer::Curve::kLinear) transfer_define = "#define CAMERA_TRANSFER_LINEAR\n";
  auto composite = gles::Program::fromEmbedded("ground_composite.vert", "ground_composite.frag", transfer_define, error);
  if (!composite) return false;
  depth_program_ = std::move(*depth);
  ground_program_ = std::move(*ground);
  composite_program_ = std::move(*composite);
  footprint_vertices_ = gles::Buffer::create();

  auto texture = gles::createTexture2D(settings.ground_texture_size_px, settings.ground_texture_size_px, GL_RGBA,
                                       GL_UNSIGNED_BYTE, GL_LINEAR, nullptr, error);
  if (!texture) return false;
  ground_texture_ = std::move(*texture);
  ground_framebuffer_ = gles::Framebuffer::create();
  glBindFramebuffer(GL_FRAMEBUFFER, ground_framebuffer_.id());
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, ground_texture_.id(), 0);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    error = "ground shadow texture framebuffer incomplete: " + gles::framebufferStatusName(status);
    return false;
  }

  // The ground square's grid, in [0, 1]^2.
  const int n = settings.region_mesh_segments;
  std::vector<float> uv;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      uv.push_back(static_cast<float>(i) / n);
      uv.push_back(static_cast<float>(j) / n);
    }
  if ((n + 1) * (n + 1) > 65536) {
    error = "ground shadow: region_mesh_segments must be at most 255 (16-bit indices)";
    return false;
  }
  region_vertices_ = gles::Buffer::create();
  glBindBuffer(GL_ARRAY_BUFFER, region_vertices_.id());
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(uv.size() * sizeof(float)), uv.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  region_indices_ = gles::Buffer::create();
  region_index_count_ = 0;
  caster_vertices_ = gles::Buffer::create();
  return gles::checkGl("GroundShadow::init", error);
}

std::string GroundShadow::depthStorageDescription() const {
  return packed_depth_ ? "depth packed in RGBA8 (16 bits in r, g)" : "OES_depth_texture";
}

bool GroundShadow::ensureShadowMaps(std::size_t count, std::string& error) {
  while (shadow_maps_.size() < count) {
    ShadowMap map;
    if (!allocateShadowMap(map, error)) return false;
    shadow_maps_.push_back(std::move(map));
  }
  while (settings_.self_shadow_maps && near_maps_.size() < count) {
    ShadowMap map;
    if (!allocateShadowMap(map, error)) return false;
    near_maps_.push_back(std::move(map));
  }
  while (settings_.self_shadow_maps && floor_maps_.size() < static_cast<std::size_t>(kFloorLightCount)) {
    ShadowMap map;
    if (!allocateShadowMap(map, error)) return false;
    floor_maps_.push_back(std::move(map));
  }
  return true;
}

bool GroundShadow::allocateShadowMap(ShadowMap& map, std::string& error) {
  const int size = settings_.shadow_map_size_px;
  {
    map.framebuffer = gles::Framebuffer::create();
    if (packed_depth_) {
      auto colour = gles::createTexture2D(size, size, GL_RGBA, GL_UNSIGNED_BYTE, GL_NEAREST, nullptr, error);
      if (!colour) return false;
      map.depth_or_colour = std::move(*colour);
      map.depth_buffer = gles::Renderbuffer::create();
      glBindRenderbuffer(GL_RENDERBUFFER, map.depth_buffer.id());
      glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT16, size, size);
      glBindFramebuffer(GL_FRAMEBUFFER, map.framebuffer.id());
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, map.depth_or_colour.id(), 0);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, map.depth_buffer.id());
    } else {
      map.depth_or_colour = gles::Texture::create();
      glBindTexture(GL_TEXTURE_2D, map.depth_or_colour.id());
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT, size, size, 0, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
      glBindTexture(GL_TEXTURE_2D, 0);
      glBindFramebuffer(GL_FRAMEBUFFER, map.framebuffer.id());
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, map.depth_or_colour.id(), 0);
    }
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
      error = "shadow map framebuffer (" + depthStorageDescription() + ") incomplete: " +
              gles::framebufferStatusName(status);
      return false;
    }
    if (!gles::checkGl("shadow map allocation", error)) return false;
  }
  return true;
}

bool GroundShadow::drawCasterDepth(const glm::mat4& light_clip_from_world, std::string& error) {
  depth_program_.use();
  glUniformMatrix4fv(depth_program_.uniform("u_light_clip_from_world"), 1, GL_FALSE, glm::value_ptr(light_clip_from_world));
  const GLint position = depth_program_.attribute("a_position_w");
  glBindBuffer(GL_ARRAY_BUFFER, caster_vertices_.id());
  glEnableVertexAttribArray(static_cast<GLuint>(position));
  glVertexAttribPointer(static_cast<GLuint>(position), 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glDrawArrays(GL_TRIANGLES, 0, caster_vertex_count_);
  glDisableVertexAttribArray(static_cast<GLuint>(position));
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  return gles::checkGl("shadow depth pass", error);
}

bool GroundShadow::update(const std::vector<ibl::ShadowLight>& lights, const ibl::ShadowCaster& caster,
                          std::string& error) {
  shadow_passes_last_update_ = 0;
  has_shadow_ = false;
  self_shadow_lights_.clear();
  floor_self_shadows_.clear();
  if (lights.empty()) return true;
  if (!ensureShadowMaps(lights.size(), error)) return false;
  region_ = ibl::groundShadowRegion(caster, lights, settings_.max_region_half_size_m);

  const bool mesh = caster.shape == ibl::ShadowCaster::Shape::kMesh;
  if (!mesh || caster.mesh_triangles_w != uploaded_mesh_) {
    const std::vector<glm::vec3> built = mesh ? std::vector<glm::vec3>{} : casterTriangles(caster);
    const std::vector<glm::vec3>& triangles = mesh && caster.mesh_triangles_w ? *caster.mesh_triangles_w : built;
    glBindBuffer(GL_ARRAY_BUFFER, caster_vertices_.id());
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(triangles.size() * sizeof(glm::vec3)), triangles.data(),
                 mesh ? GL_STATIC_DRAW : GL_DYNAMIC_DRAW);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    caster_vertex_count_ = static_cast<GLsizei>(triangles.size());
    uploaded_mesh_ = mesh ? caster.mesh_triangles_w : nullptr;
  }

  // 1. One depth map per light.
  const glm::dvec3 centre = caster.boundingCentre();
  const double radius = caster.boundingRadius();
  std::vector<LightView> views;
  const int size = settings_.shadow_map_size_px;
  glDisable(GL_BLEND);
  // Each map keeps the object's far side as seen from the light (depth test
  // GREATER over a map cleared to 0, "empty"): that is the surface nearest
  // the ground behind it, so the occluder distance t that sets the penumbra
  // (PCSS) is measured to where the light actually grazes past the object,
  // not through it. With the near side, a ground point under a 7 cm sphere
  // took its penumbra as if the sphere were a disc 7 cm higher, and came out
  // lit under the object.
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);
  glDepthMask(GL_TRUE);
  // The far side of a closed object is where its surface turns away from
  // the light, so the faces toward the light are culled: they would only
  // lose the depth test (casterTriangles winds both shapes counter-clockwise
  // seen from outside; the light's view is a right-handed camera looking
  // along -direction). That halves the triangles rasterised: 9 -> 4 ms for
  // 8 maps on llvmpipe.
  // A user's mesh need not be closed (a leaf, a sign): its faces are all
  // kept, the depth test alone keeping the far side.
  if (caster.shape == ibl::ShadowCaster::Shape::kMesh)
    glDisable(GL_CULL_FACE);
  else
    glEnable(GL_CULL_FACE);
  glCullFace(GL_FRONT);
  glFrontFace(GL_CCW);
  for (std::size_t i = 0; i < lights.size(); ++i) {
    views.push_back(lightViewFor(lights[i].direction_w, centre, radius));
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_maps_[i].framebuffer.id());
    glViewport(0, 0, size, size);
    glClearColor(0.0f, 0.0f, 0.0f, 0.0f);  // packed: depth 0, "empty"
    glClearDepthf(0.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (!drawCasterDepth(glm::mat4(views.back().clip_from_world), error)) return false;
    ++shadow_passes_last_update_;
  }
  // 1b. The near side, for the object's shadow on itself: the surface
  // nearest the light (depth test LESS over a map cleared to 1). The faces
  // away from the light are culled for a closed shape; a mesh keeps all.
  self_shadow_lights_.clear();
  if (settings_.self_shadow_maps) {
    glDepthFunc(GL_LESS);
    glCullFace(GL_BACK);
    for (std::size_t i = 0; i < lights.size(); ++i) {
      glBindFramebuffer(GL_FRAMEBUFFER, near_maps_[i].framebuffer.id());
      glViewport(0, 0, size, size);
      glClearColor(1.0f, 1.0f, 0.0f, 1.0f);  // packed: packDepth(1), "empty"
      glClearDepthf(1.0f);
      glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
      if (!drawCasterDepth(glm::mat4(views[i].clip_from_world), error)) return false;
      ++shadow_passes_last_update_;
      SelfShadowLight light;
      light.map = near_maps_[i].depth_or_colour.id();
      light.clip_from_world = glm::mat4(views[i].clip_from_world);
      light.direction_w = glm::vec3(lights[i].direction_w);
      light.rgb = glm::vec3(lights[i].rgb);
      light.depth_range_m = static_cast<float>(views[i].depth_m);
      light.width_m = static_cast<float>(views[i].width_m);
      self_shadow_lights_.push_back(light);
    }
    // And from below the horizon: the floor's light, which no dome light
    // carries (they are all above it). Directions 30 degrees down, so that
    // a face turned up to 60 degrees still has one in front of it (the
    // floor it sees lies low and outward).
    const double elevation = glm::radians(kFloorLightElevationDeg);
    for (int k = 0; k < kFloorLightCount; ++k) {
      const double azimuth = 2.0 * M_PI * k / kFloorLightCount;
      const glm::dvec3 direction(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                                 std::sin(elevation));
      const LightView below = lightViewFor(direction, centre, radius);
      ShadowMap& map = floor_maps_[static_cast<std::size_t>(k)];
      glBindFramebuffer(GL_FRAMEBUFFER, map.framebuffer.id());
      glViewport(0, 0, size, size);
      glClearColor(1.0f, 1.0f, 0.0f, 1.0f);
      glClearDepthf(1.0f);
      glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
      if (!drawCasterDepth(glm::mat4(below.clip_from_world), error)) return false;
      ++shadow_passes_last_update_;
      SelfShadowLight light;
      light.map = map.depth_or_colour.id();
      light.clip_from_world = glm::mat4(below.clip_from_world);
      light.direction_w = glm::vec3(direction);
      light.depth_range_m = static_cast<float>(below.depth_m);
      light.width_m = static_cast<float>(below.width_m);
      floor_self_shadows_.push_back(light);
    }
    glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    // Strongest first: a GPU with fewer texture units reads the first ones.
    std::stable_sort(self_shadow_lights_.begin(), self_shadow_lights_.end(),
                     [](const SelfShadowLight& a, const SelfShadowLight& b) {
                       return a.rgb.r + a.rgb.g + a.rgb.b > b.rgb.r + b.rgb.g + b.rgb.b;
                     });
  }
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glDepthFunc(GL_LESS);
  glClearDepthf(1.0f);

  // 2. The ground's fraction, 1 - sum_i share_i hidden_i: the texture is
  // cleared to 1 and each light subtracts its share (blending dest - src)
  // over only the ground its shadow can reach. A low light's shadow is a
  // long streak and a high one's a small patch, so most of the square is
  // left to the lights that do reach it (the whole square per light was
  // 40 ms of a 48 ms update on llvmpipe). Each light's share is rounded to
  // 8 bits on its own: a texel under k lights' penumbrae gets k roundings
  // of at most half a step.
  const int ground_size = settings_.ground_texture_size_px;
  glBindFramebuffer(GL_FRAMEBUFFER, ground_framebuffer_.id());
  glViewport(0, 0, ground_size, ground_size);
  glClearColor(1.0f, 1.0f, 1.0f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
  ground_program_.use();
  glUniform2f(ground_program_.uniform("u_region_centre_w"), static_cast<float>(region_.centre_w.x),
              static_cast<float>(region_.centre_w.y));
  glUniform1f(ground_program_.uniform("u_region_half_size_m"), static_cast<float>(region_.half_size_m));
  glUniform1f(ground_program_.uniform("u_map_width_m"), static_cast<float>(views[0].width_m));
  glUniform1f(ground_program_.uniform("u_depth_range_m"), static_cast<float>(views[0].depth_m));
  glUniform1f(ground_program_.uniform("u_texel_uv"), 1.0f / static_cast<float>(size));
  glUniform1f(ground_program_.uniform("u_bias01"), kShadowBias01);
  const std::array<glm::vec2, kShadowTaps> taps = shadowDiscTaps();
  glUniform2fv(ground_program_.uniform("u_taps[0]"), kShadowTaps, glm::value_ptr(taps[0]));
  glUniform1i(ground_program_.uniform("u_shadow_map"), 0);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_REVERSE_SUBTRACT);  // destination - source
  glBlendFunc(GL_ONE, GL_ONE);
  const GLint position = ground_program_.attribute("a_position");
  glBindBuffer(GL_ARRAY_BUFFER, footprint_vertices_.id());
  glEnableVertexAttribArray(static_cast<GLuint>(position));
  glVertexAttribPointer(static_cast<GLuint>(position), 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  glActiveTexture(GL_TEXTURE0);
  for (std::size_t i = 0; i < lights.size(); ++i) {
    glBindTexture(GL_TEXTURE_2D, shadow_maps_[i].depth_or_colour.id());
    glUniformMatrix4fv(ground_program_.uniform("u_light_clip_from_world"), 1, GL_FALSE,
                       glm::value_ptr(glm::mat4(views[i].clip_from_world)));
    glUniform3f(ground_program_.uniform("u_share"), static_cast<float>(lights[i].share_rgb.r),
                static_cast<float>(lights[i].share_rgb.g), static_cast<float>(lights[i].share_rgb.b));
    const double tan_cone = std::tan(std::min(lights[i].cone_radius_rad, 1.2));
    glUniform1f(ground_program_.uniform("u_tan_cone"), static_cast<float>(tan_cone));
    // On the ground z = 0, a step of the map's (right, up) by one uv (one
    // frustum width) moves the depth by (right.z, up.z) / d.z widths; the
    // frustum is as deep as it is wide.
    const glm::vec2 gradient(views[i].ground_depth_gradient_per_uv);
    glUniform2f(ground_program_.uniform("u_ground_gradient"), gradient.x, gradient.y);
    const std::array<glm::dvec2, 4> corners = shadowFootprintNdc(views[i], tan_cone, size, region_);
    const float quad[8] = {static_cast<float>(corners[0].x), static_cast<float>(corners[0].y),
                           static_cast<float>(corners[1].x), static_cast<float>(corners[1].y),
                           static_cast<float>(corners[2].x), static_cast<float>(corners[2].y),
                           static_cast<float>(corners[3].x), static_cast<float>(corners[3].y)};
    glBufferData(GL_ARRAY_BUFFER, sizeof(quad), quad, GL_STREAM_DRAW);
    glDrawArrays(GL_TRIANGLE_FAN, 0, 4);
  }
  glDisableVertexAttribArray(static_cast<GLuint>(position));
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glDisable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBindTexture(GL_TEXTURE_2D, 0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (!gles::checkGl("ground shadow pass", error)) return false;
  // The composite draws, every frame, only the grid cells the shadow darkens
  // by at least one 8-bit step: with low lights the shadows are long
  // streaks, and their bounding box was half a 640x480 frame (4 ms a frame
  // on llvmpipe), most of it left unchanged.
  const auto fraction = readFraction(error);
  if (!fraction) return false;
  const int segments = settings_.region_mesh_segments;
  const std::vector<bool> cells = darkeningCells(*fraction, ground_size, segments);
  std::vector<GLushort> indices;
  const auto at = [&](int a, int b) { return static_cast<GLushort>(b * (segments + 1) + a); };
  for (int j = 0; j < segments; ++j)
    for (int i = 0; i < segments; ++i)
      if (cells[static_cast<std::size_t>(j) * segments + i])
        indices.insert(indices.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)});
  region_index_count_ = static_cast<GLsizei>(indices.size());
  if (indices.empty()) return true;  // nothing darkens the ground by a step: nothing to draw
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, region_indices_.id());
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(GLushort)), indices.data(),
               GL_DYNAMIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  has_shadow_ = true;
  return gles::checkGl("ground shadow cells", error);
}

bool GroundShadow::drawOnCameraImage(const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                                     const CameraFrameTexture& camera_frame, std::string& error, double exposure_gain) {
  if (!has_shadow_) return true;
  composite_program_.use();
  glUniform1f(composite_program_.uniform("u_exposure_gain"), static_cast<float>(exposure_gain));
  glUniform2f(composite_program_.uniform("u_region_centre_w"), static_cast<float>(region_.centre_w.x),
              static_cast<float>(region_.centre_w.y));
  glUniform1f(composite_program_.uniform("u_region_half_size_m"), static_cast<float>(region_.half_size_m));
  const glm::mat3 rotation(pose.R_cam_from_world);
  glUniformMatrix3fv(composite_program_.uniform("u_rotation_cam_from_world"), 1, GL_FALSE, glm::value_ptr(rotation));
  glUniform3f(composite_program_.uniform("u_translation_cam_from_world"), static_cast<float>(pose.t_cam_from_world.x),
              static_cast<float>(pose.t_cam_from_world.y), static_cast<float>(pose.t_cam_from_world.z));
  glUniform4f(composite_program_.uniform("u_distortion"), static_cast<float>(camera.distortion[0]),
              static_cast<float>(camera.distortion[1]), static_cast<float>(camera.distortion[2]),
              static_cast<float>(camera.distortion[3]));
  glUniform1f(composite_program_.uniform("u_distortion_k3"), static_cast<float>(camera.distortion[4]));
  glUniform2f(composite_program_.uniform("u_focal_px"), static_cast<float>(camera.fx_px), static_cast<float>(camera.fy_px));
  glUniform2f(composite_program_.uniform("u_principal_px"), static_cast<float>(camera.cx_px),
              static_cast<float>(camera.cy_px));
  glUniform2f(composite_program_.uniform("u_image_size_px"), static_cast<float>(camera.width_px),
              static_cast<float>(camera.height_px));
  if (settings_.camera_transfer.curve == ibl::CameraTransfer::Curve::kGamma)
    glUniform1f(composite_program_.uniform("u_camera_gamma"), static_cast<float>(settings_.camera_transfer.gamma));
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, camera_frame.texture());
  glUniform1i(composite_program_.uniform("u_camera"), 0);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, ground_texture_.id());
  glUniform1i(composite_program_.uniform("u_fraction"), 1);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  const GLint uv = composite_program_.attribute("a_region_uv");
  glBindBuffer(GL_ARRAY_BUFFER, region_vertices_.id());
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, region_indices_.id());
  glEnableVertexAttribArray(static_cast<GLuint>(uv));
  glVertexAttribPointer(static_cast<GLuint>(uv), 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  glDrawElements(GL_TRIANGLES, region_index_count_, GL_UNSIGNED_SHORT, nullptr);
  glDisableVertexAttribArray(static_cast<GLuint>(uv));
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  glBindTexture(GL_TEXTURE_2D, 0);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, 0);
  return gles::checkGl("ground shadow composite", error);
}

std::optional<std::vector<glm::vec3>> GroundShadow::readFraction(std::string& error) const {
  const int n = settings_.ground_texture_size_px;
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(n) * n * 4);
  glBindFramebuffer(GL_FRAMEBUFFER, ground_framebuffer_.id());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, n, n, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (!gles::checkGl("ground shadow read-back", error)) return std::nullopt;
  std::vector<glm::vec3> fraction(static_cast<std::size_t>(n) * n);
  for (std::size_t i = 0; i < fraction.size(); ++i)
    fraction[i] = glm::vec3(rgba[i * 4], rgba[i * 4 + 1], rgba[i * 4 + 2]) / 255.0f;
  return fraction;
}

glm::dvec2 GroundShadow::groundPointOfTexel(int i, int j) const {
  const double n = settings_.ground_texture_size_px;
  return region_.centre_w + region_.half_size_m * glm::dvec2((2.0 * i + 1.0) / n - 1.0, (2.0 * j + 1.0) / n - 1.0);
}

}  // namespace probelight::passes
