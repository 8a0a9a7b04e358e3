// A user's model (issue 16's "Cost"): milliseconds per frame of the
// model's draw (passes/model_renderer) against its triangle count and
// against the number of texture maps its material reads, each next to a
// plain unlit draw of the same mesh, and the model's shadow pass
// (passes/ground_shadow with the self-shadow maps, for the dome's lights).
//
// The unlit draw: the same triangles (placed in W, as the renderer uploads
// them), the same index type, the same projection (camera_projection.glsl
// with the calibrated distortion, as model_object.vert), the same 640x480
// target, depth test and back-face culling, and a fragment shader that
// writes one constant colour. lit / unlit is what the materials' shading
// costs over rasterising the mesh; issue 16 wants it within 2x. Speed is
// never asserted (a test would fail on a loaded machine): it is a counter.
//
// Each iteration draws lit and unlit back to back (the order alternating),
// each into a target cleared and finished beforehand, so only the draw and
// its glFinish are timed; the benchmark's own time is the lit draw's
// (manual time), and the counters are the medians of both. The meshes are
// generated spheres (model/generated_models.hpp) of 8 cm radius resting on
// the tag, seen from 32 cm as the model tests see theirs; set-up (meshes,
// uploads, maps, shadows) is made once per configuration and kept, outside
// every timed loop, in this file's own headless EGL context. A plain table
// is printed at the end (docs/benchmarks.md, "A user's model").
//
// Rows (all under model/, so --benchmark_filter=model runs them alone):
//   model/tris:N          lit (no self-shadow, edges off) and unlit draws
//   model/maps:K          the 10k sphere with K of base colour, metallic-
//                         roughness, normal, occlusion, emissive (1024^2 each)
//   model/self_shadow/tris:N  the lit draw with the self-shadow, edges off
//   model/kiosk/tris:N    the draw as the kiosk makes it: kKioskEdgeSamples
//                         and the self-shadow from the dome's lights
//   model/shadow_pass/tris:N  GroundShadow::update for the mesh caster
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <GLES2/gl2.h>
#include <benchmark/benchmark.h>
#include <glm/glm.hpp>

#include "core/types.hpp"
#include "gles/capabilities.hpp"
#include "gles/egl_context.hpp"
#include "gles/gl_objects.hpp"
#include "gles/render_target.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/ground_shadow.hpp"
#include "ibl/light_dome.hpp"
#include "model/generated_models.hpp"
#include "model/mesh_model.hpp"
#include "model/model_placement.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "passes/ground_shadow.hpp"
#include "passes/model_renderer.hpp"
#include "passes/object_uniforms.hpp"
#include "stages/scene_object.hpp"

namespace probelight::bench {
namespace {

constexpr double kSphereRadiusM = 0.08;
constexpr int kTexturePx = 1024;
constexpr int kMapsRowRings = 50;  // the 10k sphere
// Rings of a sphere of about 1k, 10k, 100k and 1M triangles (4 r^2 - 4 r).
constexpr std::pair<const char*, int> kTriangleRows[] = {{"1k", 16}, {"10k", 50}, {"100k", 158}, {"1M", 500}};
const char* const kMapNames[] = {"base colour", "metallic-roughness", "normal", "occlusion", "emissive"};

CameraIntrinsics benchCamera() {
  CameraIntrinsics camera;  // as the GPU tests' camera: 640x480 with distortion
  camera.width_px = 640;
  camera.height_px = 480;
  camera.fx_px = 530.0;
  camera.fy_px = 527.0;
  camera.cx_px = 322.3;
  camera.cy_px = 236.8;
  camera.distortion = {-0.12, 0.06, 0.0012, -0.0008, -0.01};
  return camera;
}

PoseCamFromWorld lookAt(const glm::dvec3& eye_w, const glm::dvec3& target_w) {
  const glm::dvec3 forward = glm::normalize(target_w - eye_w);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, glm::dvec3(0.0, 0.0, 1.0)));
  const glm::dvec3 down = glm::cross(forward, right);
  PoseCamFromWorld pose;
  pose.R_cam_from_world = glm::transpose(glm::dmat3(right, down, forward));
  pose.t_cam_from_world = -(pose.R_cam_from_world * eye_w);
  return pose;
}

// A smooth sky with a warm window lobe (the GPU tests' analytic environment),
// so the dome fit finds lights and the glossy maps have structure.
glm::dvec3 benchEnvironment(const glm::dvec3& direction) {
  const glm::dvec3 d = glm::normalize(direction);
  const double window = std::pow(std::max(0.0, glm::dot(d, glm::normalize(glm::dvec3(0.6, 0.3, 0.74)))), 6.0);
  return {0.10 + 0.25 * (0.5 + 0.5 * d.z) + 0.55 * window, 0.18 + 0.12 * (0.5 + 0.5 * d.x) + 0.35 * window,
          0.22 + 0.18 * (0.5 + 0.5 * d.y) * (0.5 + 0.5 * d.z) + 0.15 * window};
}

double medianOf(std::vector<double> values) {
  if (values.empty()) return NAN;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// ---------------------------------------------------------------------------
// Shared set-up: the context, the target and the environment maps.

struct Setup {
  std::unique_ptr<gles::EglContext> context;
  std::string gl_error;  // non-empty: no benchmarks
  gles::Capabilities capabilities;
  CameraIntrinsics camera = benchCamera();
  PoseCamFromWorld pose = lookAt({0.03, -0.32, 0.12}, {0.0, 0.0, kSphereRadiusM});
  gles::RenderTarget target;
  passes::EnvironmentMaps maps;
  std::vector<ibl::ShadowLight> lights;  // the dome's, fitted to the environment
  passes::CameraFrameTexture frame;      // a grey camera frame, for the floor the kiosk's model reflects
};

Setup& setup() {
  static Setup* instance = [] {
    auto* s = new Setup;  // never freed: its GL objects would need the context at exit
    s->context = gles::EglContext::createHeadless(s->gl_error);
    if (!s->context) {
      std::fprintf(stderr, "model bench: no GL context, skipped: %s\n", s->gl_error.c_str());
      return s;
    }
    s->capabilities = gles::probeCapabilities();
    std::string& error = s->gl_error;
    if (!s->target.init(s->camera.width_px, s->camera.height_px, error) ||
        !s->maps.init(s->capabilities, {}, error) || !s->frame.init(s->capabilities, error))
      return s;
    ImageRGB8 grey;
    grey.resize(s->camera.width_px, s->camera.height_px);
    std::fill(grey.pixels.begin(), grey.pixels.end(), 110);
    if (!s->frame.upload(grey, error)) return s;
    ibl::CubeMapRGB environment(s->maps.settings().reflection_face_size);
    for (int face = 0; face < ibl::kCubeFaceCount; ++face)
      for (int y = 0; y < environment.face_size; ++y)
        for (int x = 0; x < environment.face_size; ++x)
          environment.texel(face, x, y) =
              glm::vec3(benchEnvironment(ibl::cubeTexelCenterDirection(face, x, y, environment.face_size)));
    if (!s->maps.setReflection(environment, error) || !s->maps.updateDiffuse(error) || !s->maps.updateGlossy(error))
      return s;
    s->lights = ibl::groundShadowLights(ibl::fitLightDome(environment, nullptr));
    std::fprintf(stderr, "model bench: GL: %s (%s); %zu dome lights cast shadows\n",
                 s->capabilities.summary().c_str(), s->context->platformName().c_str(), s->lights.size());
    return s;
  }();
  return *instance;
}

bool requireGl(benchmark::State& state) {
  Setup& s = setup();
  std::string error;
  if (!s.context) {
    state.SkipWithError(("no headless EGL context: " + s.gl_error).c_str());
    return false;
  }
  if (!s.context->makeCurrent(error)) {
    state.SkipWithError(error.c_str());
    return false;
  }
  if (!s.gl_error.empty()) {
    state.SkipWithError(("model bench set-up failed: " + s.gl_error).c_str());
    return false;
  }
  return true;
}

// The target bound, cleared and finished: what each timed draw starts from.
void clearTarget() {
  Setup& s = setup();
  s.target.bind();
  glDepthMask(GL_TRUE);
  glClearColor(0.35f, 0.35f, 0.35f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glFinish();
}

// Pixels that differ from the clear colour (the model's coverage).
int coveredPixels(std::string& error) {
  ImageRGB8 image;
  if (!setup().target.readRGB(image, error)) return -1;
  int covered = 0;
  const std::uint8_t clear = static_cast<std::uint8_t>(std::lround(0.35 * 255.0));
  for (std::size_t i = 0; i + 2 < image.pixels.size(); i += 3)
    covered += image.pixels[i] != clear || image.pixels[i + 1] != clear || image.pixels[i + 2] != clear;
  return covered;
}

// ---------------------------------------------------------------------------
// The plain unlit draw of a mesh.

constexpr const char* kUnlitVertex = R"(#version 100
#include "camera_projection.glsl"
attribute vec3 a_position_w;
uniform mat3 u_rotation_cam_from_world;
uniform vec3 u_translation_cam_from_world;
uniform vec4 u_distortion;
uniform float u_distortion_k3;
uniform vec2 u_focal_px;
uniform vec2 u_principal_px;
uniform vec2 u_image_size_px;
uniform vec2 u_depth_range_m;
void main() {
  vec3 position_cam = u_rotation_cam_from_world * a_position_w + u_translation_cam_from_world;
  float z = position_cam.z;
  vec2 distorted = distortNormalized(position_cam.xy / z, u_distortion, u_distortion_k3);
  vec2 pixel = u_focal_px * distorted + u_principal_px;
  vec2 ndc = vec2(2.0 * (pixel.x + 0.5) / u_image_size_px.x - 1.0, 1.0 - 2.0 * (pixel.y + 0.5) / u_image_size_px.y);
  float depth_ndc = 2.0 * (z - u_depth_range_m.x) / (u_depth_range_m.y - u_depth_range_m.x) - 1.0;
  gl_Position = vec4(ndc * z, depth_ndc * z, z);
}
)";

constexpr const char* kUnlitFragment = R"(#version 100
void main() { gl_FragColor = vec4(0.8, 0.8, 0.8, 1.0); }
)";

class UnlitMesh {
 public:
  bool init(const model::MeshModel& model, const glm::dmat4& world_from_model, std::string& error) {
    std::optional<gles::Program> program =
        gles::Program::fromSources("unlit_bench.vert", kUnlitVertex, "unlit_bench.frag", kUnlitFragment, "", error);
    if (!program) return false;
    program_ = std::move(*program);
    std::vector<glm::vec3> positions;
    std::vector<std::uint32_t> indices;
    for (const model::Primitive& primitive : model.primitives) {
      const auto base = static_cast<std::uint32_t>(positions.size());
      for (const glm::vec3& p : primitive.positions_m)
        positions.push_back(glm::vec3(world_from_model * glm::dvec4(glm::dvec3(p), 1.0)));
      for (std::uint32_t index : primitive.indices) indices.push_back(base + index);
    }
    // As the renderer: 16-bit indices where they suffice, else 32-bit.
    short_indices_ = positions.size() <= 65536;
    if (!short_indices_ && !setup().capabilities.element_index_uint) {
      error = "unlit draw: more than 65536 vertices and no OES_element_index_uint";
      return false;
    }
    vertices_ = gles::Buffer::create();
    glBindBuffer(GL_ARRAY_BUFFER, vertices_.id());
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(positions.size() * sizeof(glm::vec3)), positions.data(),
                 GL_STATIC_DRAW);
    indices_ = gles::Buffer::create();
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, indices_.id());
    if (short_indices_) {
      const std::vector<std::uint16_t> shorts(indices.begin(), indices.end());
      glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(shorts.size() * 2), shorts.data(), GL_STATIC_DRAW);
    } else {
      glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * 4), indices.data(), GL_STATIC_DRAW);
    }
    index_count_ = static_cast<GLsizei>(indices.size());
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
    return gles::checkGl("UnlitMesh::init", error);
  }

  // Into the bound framebuffer, with the renderer's depth test and culling.
  bool draw(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, std::string& error) const {
    const passes::ModelRendererSettings defaults;
    program_.use();
    passes::setCameraProjectionUniforms(program_, camera, pose, defaults.near_m, defaults.far_m);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
    glFrontFace(GL_CCW);
    glCullFace(GL_BACK);
    glEnable(GL_CULL_FACE);
    const GLint location = program_.attribute("a_position_w");
    glBindBuffer(GL_ARRAY_BUFFER, vertices_.id());
    glEnableVertexAttribArray(static_cast<GLuint>(location));
    glVertexAttribPointer(static_cast<GLuint>(location), 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, indices_.id());
    glDrawElements(GL_TRIANGLES, index_count_, short_indices_ ? GL_UNSIGNED_SHORT : GL_UNSIGNED_INT, nullptr);
    glDisableVertexAttribArray(static_cast<GLuint>(location));
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
    glDisable(GL_CULL_FACE);
    glDisable(GL_DEPTH_TEST);
    return gles::checkGl("UnlitMesh::draw", error);
  }

 private:
  gles::Program program_;
  gles::Buffer vertices_, indices_;
  GLsizei index_count_ = 0;
  bool short_indices_ = true;
};

// ---------------------------------------------------------------------------
// Models: a sphere of `rings`, with `maps` of the five texture maps.

model::TextureImage generatedImage(const std::string& name, int map) {
  model::TextureImage image;
  image.name = name;
  image.width = image.height = kTexturePx;
  image.rgba.resize(static_cast<std::size_t>(kTexturePx) * kTexturePx * 4);
  for (int y = 0; y < kTexturePx; ++y)
    for (int x = 0; x < kTexturePx; ++x) {
      const double u = (x + 0.5) / kTexturePx, v = (y + 0.5) / kTexturePx;
      const double wave = 0.5 + 0.5 * std::sin(2.0 * std::numbers::pi * 24.0 * u) * std::sin(2.0 * std::numbers::pi * 12.0 * v);
      const bool checker = ((x / 64) + (y / 64)) % 2 == 0;
      glm::dvec3 c;
      switch (map) {
        case 0:  // base colour (sRGB): a checker of two colours, shaded by the wave
          c = (checker ? glm::dvec3(0.85, 0.55, 0.30) : glm::dvec3(0.30, 0.45, 0.70)) * (0.7 + 0.3 * wave);
          break;
        case 1:  // metallic-roughness: G roughness 0.4-0.6, B metallic (metal squares)
          c = {1.0, 0.4 + 0.2 * wave, checker ? 1.0 : 0.0};
          break;
        case 2: {  // normal (tangent space): the wave's bumps
          const glm::dvec3 n = glm::normalize(glm::dvec3(0.4 * std::cos(2.0 * std::numbers::pi * 24.0 * u),
                                                         0.4 * std::cos(2.0 * std::numbers::pi * 12.0 * v), 1.0));
          c = 0.5 * n + 0.5;
          break;
        }
        case 3:  // occlusion in R
          c = glm::dvec3(0.6 + 0.4 * wave);
          break;
        default:  // emissive (sRGB): faint, brighter in the wave's crests
          c = glm::dvec3(0.2, 0.1, 0.05) * wave * wave;
          break;
      }
      std::uint8_t* texel = &image.rgba[(static_cast<std::size_t>(y) * kTexturePx + x) * 4];
      for (int k = 0; k < 3; ++k) texel[k] = static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(c[k], 0.0, 1.0)));
      texel[3] = 255;
    }
  return image;
}

model::MeshModel benchSphere(int rings, int maps) {
  model::Material material;
  material.name = "bench";
  material.base_color_factor = {0.8f, 0.8f, 0.8f, 1.0f};
  material.metallic_factor = 0.5f;
  material.roughness_factor = 0.5f;
  model::MeshModel model = model::sphereModel(kSphereRadiusM, rings, material);
  model::Material& m = model.materials.at(0);
  model::TextureSlot* slots[] = {&m.base_color, &m.metallic_roughness, &m.normal, &m.occlusion, &m.emissive};
  for (int map = 0; map < maps && map < 5; ++map) {
    model.images.push_back(generatedImage(kMapNames[map], map));
    slots[map]->image = static_cast<int>(model.images.size()) - 1;
  }
  if (maps >= 2) m.metallic_factor = m.roughness_factor = 1.0f;  // the texture's G and B
  if (maps >= 5) m.emissive_factor = glm::vec3(1.0f);
  return model;
}

// One mesh's GL objects, made once and kept.
struct ModelRig {
  SceneObject object;  // as the kiosk places a model (modelSceneObject)
  passes::ModelRenderer lit;
  std::unique_ptr<passes::ModelRenderer> kiosk;  // kKioskEdgeSamples, self-shadowed
  std::unique_ptr<passes::GroundShadow> shadow;  // with self_shadow_maps, updated once
  std::unique_ptr<UnlitMesh> unlit;              // only the tris rows own one
  std::size_t triangles = 0;
  std::string error;  // non-empty: set-up failed
  // Once per configuration: coverage (lit, unlit) and whether the first
  // (shader-compiling) draws are done.
  int covered_lit = -1, covered_unlit = -1, covered_kiosk = -1;
};

ModelRig& modelRig(int rings, int maps, bool with_unlit) {
  static std::map<std::pair<int, int>, ModelRig*> rigs;
  ModelRig*& rig = rigs[{rings, maps}];
  if (rig != nullptr) return *rig;
  rig = new ModelRig;  // never freed, as Setup
  Setup& s = setup();
  auto model = std::make_shared<model::MeshModel>(benchSphere(rings, maps));
  rig->triangles = model->triangleCount();
  rig->object = modelSceneObject(model, model::ModelPlacement{});
  std::string& error = rig->error;
  if (!rig->lit.init(s.capabilities, s.maps.storage(), *model, rig->object.world_from_model, {}, error)) return *rig;
  if (with_unlit) {
    rig->unlit = std::make_unique<UnlitMesh>();
    if (!rig->unlit->init(*model, rig->object.world_from_model, error)) return *rig;
  }
  return *rig;
}

// The kiosk's renderer and the shadow pass of a rig, made on first use.
bool ensureKioskAndShadow(ModelRig& rig) {
  if (rig.kiosk) return rig.error.empty();
  Setup& s = setup();
  std::string& error = rig.error;
  rig.shadow = std::make_unique<passes::GroundShadow>();
  passes::GroundShadowSettings shadow_settings;
  shadow_settings.self_shadow_maps = true;  // as ShadowsStage for a mesh caster
  if (!rig.shadow->init(s.capabilities, shadow_settings, error) || !rig.shadow->update(s.lights, rig.object.shape, error))
    return false;
  rig.kiosk = std::make_unique<passes::ModelRenderer>();
  passes::ModelRendererSettings settings;
  settings.edge_samples = passes::kKioskEdgeSamples;
  if (!rig.kiosk->init(s.capabilities, s.maps.storage(), *rig.object.model, rig.object.world_from_model, settings,
                       error) ||
      !rig.kiosk->prepareEdges(s.camera.width_px, s.camera.height_px, 0, error))
    return false;
  // As ComposeStage draws it: self-shadowed from the dome and the floor,
  // reflecting the floor beside it (the default rig's ball).
  rig.kiosk->setSelfShadow(&rig.shadow->selfShadowLights(), rig.shadow->shadowMapSizePx(), rig.shadow->packedDepth(),
                           &rig.shadow->floorSelfShadows());
  passes::ModelRenderer::NearFloor near_floor;
  near_floor.enabled = true;
  near_floor.ball_centre_w = RigGeometry{}.probe_center_w;
  near_floor.ball_radius_m = RigGeometry{}.probe_radius_m;
  near_floor.shadow = rig.shadow.get();
  near_floor.camera_frame = &s.frame;
  rig.kiosk->setNearFloor(near_floor);
  return true;
}

// ---------------------------------------------------------------------------
// Samples and the table.

struct Row {
  std::string name;
  std::size_t triangles = 0;
  int maps = 0;
  std::vector<double> lit_ms, unlit_ms;  // lit: the row's own draw (lit, kiosk or shadow pass)
  int covered_px = -1, covered_unlit_px = -1;
  std::string note;
};

// Never freed: the table is printed from a static destructor.
std::map<std::string, Row>& rows() {
  static auto* table = new std::map<std::string, Row>;
  return *table;
}
std::vector<std::string>& rowOrder() {
  static auto* order = new std::vector<std::string>;
  return *order;
}

Row& rowFor(const std::string& name) {
  auto found = rows().find(name);
  if (found != rows().end()) return found->second;
  rowOrder().push_back(name);
  Row& row = rows()[name];
  row.name = name;
  return row;
}

void printTable();

// Prints the table after main returns (stages_bench.cpp owns main).
struct TablePrinter {
  ~TablePrinter() { printTable(); }
} table_printer;

void printTable() {
  if (rows().empty()) return;
  std::fflush(stdout);
  std::printf("\nA user's model (640x480, 8 cm sphere from 32 cm; medians of per-iteration times, glFinish included;\n"
              "unlit: the same mesh, projection, depth test and culling with a constant-colour fragment shader):\n");
  std::printf("  %-26s %9s %5s %10s %10s %8s %9s  %s\n", "row", "triangles", "maps", "ms", "unlit ms", "ratio",
              "px", "");
  for (const std::string& name : rowOrder()) {
    const Row& row = rows().at(name);
    const double ms = medianOf(row.lit_ms), unlit = medianOf(row.unlit_ms);
    char unlit_text[32] = "-", ratio_text[32] = "-", px_text[32] = "-";
    if (!row.unlit_ms.empty()) {
      std::snprintf(unlit_text, sizeof unlit_text, "%.3f", unlit);
      std::snprintf(ratio_text, sizeof ratio_text, "%.2fx", ms / unlit);
    }
    if (row.covered_px >= 0) std::snprintf(px_text, sizeof px_text, "%d", row.covered_px);
    std::printf("  %-26s %9zu %5d %10.3f %10s %8s %9s  %s\n", name.c_str(), row.triangles, row.maps, ms, unlit_text,
                ratio_text, px_text, row.note.c_str());
  }
  std::fflush(stdout);
}

// ---------------------------------------------------------------------------
// The benchmarks.

// Lit (or the kiosk's) draw against the unlit draw of the same mesh,
// interleaved, the order alternating.
void drawAgainstUnlit(benchmark::State& state, const std::string& name, ModelRig& rig, passes::ModelRenderer& lit,
                      const UnlitMesh& unlit, int maps) {
  Setup& s = setup();
  Row& row = rowFor(name);
  row.triangles = rig.triangles;
  row.maps = maps;
  std::string error;
  auto drawLit = [&] { return lit.draw(s.camera, s.pose, ibl::SceneLighting{}, s.maps, error); };
  auto drawUnlit = [&] { return unlit.draw(s.camera, s.pose, error); };
  if (row.covered_px < 0) {
    // Once untimed: llvmpipe compiles a shader at its first draw; and the coverage.
    clearTarget();
    if (!drawLit() || (row.covered_px = coveredPixels(error)) < 0) {
      state.SkipWithError(error.c_str());
      return;
    }
    clearTarget();
    if (!drawUnlit() || (row.covered_unlit_px = coveredPixels(error)) < 0) {
      state.SkipWithError(error.c_str());
      return;
    }
    const passes::ModelUploadStats& stats = lit.stats();
    row.note = std::string("edges ") + passes::edgeStrategyName(stats.edges.strategy) + " x" +
               std::to_string(std::max(1, stats.edges.samples)) + ", self-shadow lights " +
               std::to_string(lit.selfShadowLightsRead()) + ", unlit px " + std::to_string(row.covered_unlit_px);
  }
  bool lit_first = true;
  for (auto _ : state) {
    double lit_ms = 0.0, unlit_ms = 0.0;
    for (int pass = 0; pass < 2; ++pass) {
      const bool is_lit = (pass == 0) == lit_first;
      clearTarget();
      const auto start = std::chrono::steady_clock::now();
      const bool ok = is_lit ? drawLit() : drawUnlit();
      glFinish();
      (is_lit ? lit_ms : unlit_ms) = msSince(start);
      if (!ok) {
        state.SkipWithError(error.c_str());
        return;
      }
    }
    lit_first = !lit_first;
    row.lit_ms.push_back(lit_ms);
    row.unlit_ms.push_back(unlit_ms);
    state.SetIterationTime(lit_ms / 1000.0);
  }
  const double lit_median = medianOf(row.lit_ms), unlit_median = medianOf(row.unlit_ms);
  state.counters["lit_ms"] = lit_median;
  state.counters["unlit_ms"] = unlit_median;
  state.counters["lit_over_unlit"] = lit_median / unlit_median;
  state.counters["triangles"] = static_cast<double>(rig.triangles);
  state.counters["covered_px"] = row.covered_px;
}

void trianglesRow(benchmark::State& state, const char* label, int rings) {
  if (!requireGl(state)) return;
  ModelRig& rig = modelRig(rings, 0, true);
  if (!rig.error.empty()) {
    state.SkipWithError(rig.error.c_str());
    return;
  }
  drawAgainstUnlit(state, std::string("model/tris:") + label, rig, rig.lit, *rig.unlit, 0);
}

void mapsRow(benchmark::State& state, int maps) {
  if (!requireGl(state)) return;
  ModelRig& plain = modelRig(kMapsRowRings, 0, true);  // the same mesh's unlit draw
  ModelRig& rig = maps == 0 ? plain : modelRig(kMapsRowRings, maps, false);
  if (!plain.error.empty() || !rig.error.empty()) {
    state.SkipWithError((plain.error + rig.error).c_str());
    return;
  }
  drawAgainstUnlit(state, "model/maps:" + std::to_string(maps), rig, rig.lit, *plain.unlit, maps);
  state.counters["textures"] = static_cast<double>(rig.lit.stats().textures);
}

void kioskRow(benchmark::State& state, const char* label, int rings) {
  if (!requireGl(state)) return;
  ModelRig& rig = modelRig(rings, 0, true);
  if (!rig.error.empty() || !ensureKioskAndShadow(rig)) {
    state.SkipWithError(rig.error.c_str());
    return;
  }
  drawAgainstUnlit(state, std::string("model/kiosk/tris:") + label, rig, *rig.kiosk, *rig.unlit, 0);
  state.counters["self_shadow_lights"] = rig.kiosk->selfShadowLightsRead();
  state.counters["edge_samples"] = std::max(1, rig.kiosk->stats().edges.samples);
}

// The lit draw with the self-shadow from the dome's lights, edges off: what
// the self-shadow alone adds to the model/tris row.
void selfShadowRow(benchmark::State& state, const char* label, int rings) {
  if (!requireGl(state)) return;
  ModelRig& rig = modelRig(rings, 0, true);
  if (!rig.error.empty() || !ensureKioskAndShadow(rig)) {
    state.SkipWithError(rig.error.c_str());
    return;
  }
  rig.lit.setSelfShadow(&rig.shadow->selfShadowLights(), rig.shadow->shadowMapSizePx(), rig.shadow->packedDepth(),
                        &rig.shadow->floorSelfShadows());
  drawAgainstUnlit(state, std::string("model/self_shadow/tris:") + label, rig, rig.lit, *rig.unlit, 0);
  state.counters["self_shadow_lights"] = rig.lit.selfShadowLightsRead();
  rig.lit.setSelfShadow(nullptr, 0, false);  // the tris rows draw without
}

void shadowRow(benchmark::State& state, const char* label, int rings) {
  if (!requireGl(state)) return;
  Setup& s = setup();
  ModelRig& rig = modelRig(rings, 0, true);
  if (!rig.error.empty() || !ensureKioskAndShadow(rig)) {  // its update() ran once there, untimed
    state.SkipWithError(rig.error.c_str());
    return;
  }
  Row& row = rowFor(std::string("model/shadow_pass/tris:") + label);
  row.triangles = rig.triangles;
  std::string error;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const bool ok = rig.shadow->update(s.lights, rig.object.shape, error);
    glFinish();
    const double ms = msSince(start);
    if (!ok) {
      state.SkipWithError(error.c_str());
      return;
    }
    row.lit_ms.push_back(ms);
    state.SetIterationTime(ms / 1000.0);
  }
  row.note = std::to_string(s.lights.size()) + " lights, " + std::to_string(rig.shadow->shadowPassesLastUpdate()) +
             " passes, " + rig.shadow->depthStorageDescription() + ", " +
             std::to_string(rig.shadow->shadowMapSizePx()) + " px maps";
  state.counters["lights"] = static_cast<double>(s.lights.size());
  state.counters["passes"] = rig.shadow->shadowPassesLastUpdate();
  state.counters["triangles"] = static_cast<double>(rig.triangles);
}

// The 1M rows run a fixed few iterations; the rest a short minimum time.
template <typename Family>
Family* paced(Family* benchmark, int rings) {
  benchmark->Unit(benchmark::kMillisecond)->UseManualTime();
  if (rings >= 500)
    benchmark->Iterations(4);
  else
    benchmark->MinTime(0.3);
  return benchmark;
}

int registerAll() {
  for (const auto& [label, rings] : kTriangleRows)
    paced(benchmark::RegisterBenchmark((std::string("model/tris:") + label).c_str(),
                                       [label = label, rings = rings](benchmark::State& state) {
                                         trianglesRow(state, label, rings);
                                       }),
          rings);
  for (int maps = 0; maps <= 5; ++maps)
    paced(benchmark::RegisterBenchmark(("model/maps:" + std::to_string(maps)).c_str(),
                                       [maps](benchmark::State& state) { mapsRow(state, maps); }),
          kMapsRowRings);
  for (const auto& [label, rings] : kTriangleRows)
    paced(benchmark::RegisterBenchmark((std::string("model/self_shadow/tris:") + label).c_str(),
                                       [label = label, rings = rings](benchmark::State& state) {
                                         selfShadowRow(state, label, rings);
                                       }),
          rings);
  for (const auto& [label, rings] : kTriangleRows)
    paced(benchmark::RegisterBenchmark((std::string("model/kiosk/tris:") + label).c_str(),
                                       [label = label, rings = rings](benchmark::State& state) {
                                         kioskRow(state, label, rings);
                                       }),
          rings);
  for (const auto& [label, rings] : kTriangleRows)
    paced(benchmark::RegisterBenchmark((std::string("model/shadow_pass/tris:") + label).c_str(),
                                       [label = label, rings = rings](benchmark::State& state) {
                                         shadowRow(state, label, rings);
                                       }),
          rings);
  return 0;
}

// Registered before main (stages_bench.cpp's), which runs them with the rest.
const int registered = registerAll();

}  // namespace
}  // namespace probelight::bench
