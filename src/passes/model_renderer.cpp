#include "passes/model_renderer.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <limits>
#include <numeric>

#include <glm/gtc/type_ptr.hpp>
#include <opencv2/imgproc.hpp>

#include "ibl/metallic_roughness.hpp"
#include "ibl/near_floor.hpp"
#include "model/vertex_attributes.hpp"
#include "passes/object_uniforms.hpp"

namespace probelight::passes {

namespace {

constexpr const char* kSlotNames[] = {"base colour", "metallic-roughness", "normal", "occlusion", "emissive"};
constexpr const char* kSlotDefines[] = {"BASE_COLOR", "METALLIC_ROUGHNESS", "NORMAL", "OCCLUSION", "EMISSIVE"};
constexpr const char* kSlotUniforms[] = {"u_base_color", "u_metallic_roughness", "u_normal", "u_occlusion",
                                         "u_emissive"};

const model::TextureSlot& slotOf(const model::Material& material, int slot) {
  switch (slot) {
    case 0: return material.base_color;
    case 1: return material.metallic_roughness;
    case 2: return material.normal;
    case 3: return material.occlusion;
    default: return material.emissive;
  }
}

GLint glWrap(model::TextureWrap wrap) {
  switch (wrap) {
    case model::TextureWrap::kClampToEdge: return GL_CLAMP_TO_EDGE;
    case model::TextureWrap::kMirroredRepeat: return GL_MIRRORED_REPEAT;
    default: return GL_REPEAT;
  }
}

std::uint64_t mipChainBytes(int width, int height) {
  std::uint64_t bytes = 0;
  while (true) {
    bytes += static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height) * 4;
    if (width == 1 && height == 1) break;
    width = std::max(1, width / 2);
    height = std::max(1, height / 2);
  }
  return bytes;
}

// Where the rungs the shader reads from are bound: diffuse 0, then the
// specular rungs, the BRDF table, then the material's textures.
constexpr int kDiffuseUnit = 0;

}  // namespace

glm::mat3 textureTransformMatrix(const model::TextureSlot& slot) {
  const float c = std::cos(slot.uv_rotation_rad), s = std::sin(slot.uv_rotation_rad);
  // Column-major: m[column][row]. KHR_texture_transform's rotation matrix
  // has rows (cos, sin) and (-sin, cos).
  glm::mat3 translation(1.0f), rotation(1.0f), scale(1.0f);
  translation[2][0] = slot.uv_offset.x;
  translation[2][1] = slot.uv_offset.y;
  rotation[0][0] = c;
  rotation[1][0] = s;
  rotation[0][1] = -s;
  rotation[1][1] = c;
  scale[0][0] = slot.uv_scale.x;
  scale[1][1] = slot.uv_scale.y;
  return translation * rotation * scale;
}

std::pair<float, float> materialRoughnessRange(const model::Material& material, const model::MeshModel& model) {
  const float factor = std::clamp(std::isfinite(material.roughness_factor) ? material.roughness_factor : 1.0f, 0.0f, 1.0f);
  const int image = material.metallic_roughness.image;
  if (image < 0 || image >= static_cast<int>(model.images.size()) || model.images[image].rgba.empty())
    return {factor, factor};
  std::uint8_t lowest = 255, highest = 0;
  const std::vector<std::uint8_t>& rgba = model.images[image].rgba;
  for (std::size_t i = 1; i < rgba.size(); i += 4) {
    lowest = std::min(lowest, rgba[i]);
    highest = std::max(highest, rgba[i]);
  }
  return {factor * lowest / 255.0f, factor * highest / 255.0f};
}

int nearestPowerOfTwo(int size, int max_size) {
  int power = 1;
  while (power * 2 <= std::max(size, 1)) power *= 2;
  // Between power and 2 power: the nearer in ratio (sqrt(2) power splits them).
  if (size > power * std::sqrt(2.0)) power *= 2;
  while (power > std::max(max_size, 1)) power /= 2;
  return std::max(power, 1);
}

bool ModelRenderer::init(const gles::Capabilities& capabilities, CubeStorage storage, const model::MeshModel& model,
                         const glm::dmat4& world_from_model, const ModelRendererSettings& settings,
                         std::string& error) {
  const auto start = std::chrono::steady_clock::now();
  settings_ = settings;
  capabilities_ = capabilities;
  storage_ = storage;
  materials_.clear();
  pieces_.clear();
  textures_.clear();
  programs_.clear();
  warnings_.clear();
  stats_ = ModelUploadStats{};
  edge_request_ = EdgeAntialiasing{};
  edge_width_px_ = edge_height_px_ = 0;
  edge_layer_ = EdgeLayer{};
  bounds_min_w_ = glm::dvec3(std::numeric_limits<double>::infinity());
  bounds_max_w_ = glm::dvec3(-std::numeric_limits<double>::infinity());
  if (!(settings.near_m > 0.0 && settings.far_m > settings.near_m)) {
    error = "ModelRenderer: depth range needs 0 < near_m < far_m";
    return false;
  }

  // The split-sum table: 8-bit luminance (scale) and alpha (bias), core GLES2.
  const ibl::EnvironmentBrdfTable table;
  brdf_table_size_ = table.size();
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  auto brdf = gles::createTexture2D(table.size(), table.size(), GL_LUMINANCE_ALPHA, GL_UNSIGNED_BYTE, GL_LINEAR,
                                    table.luminanceAlpha().data(), error);
  if (!brdf) return false;
  brdf_table_ = std::move(*brdf);

  // Materials, glTF's default (index -1) as the last.
  std::vector<model::Material> sources = model.materials;
  sources.push_back(model::Material{});
  sources.back().name = "glTF default";
  for (const model::Material& material : sources) {
    MaterialState state;
    state.material = material;
    std::tie(state.min_roughness, state.max_roughness) = materialRoughnessRange(material, model);
    for (int slot = 0; slot < kSlotCount; ++slot) {
      const model::TextureSlot& texture_slot = slotOf(material, slot);
      if (!texture_slot.present()) continue;
      state.textures[static_cast<size_t>(slot)] = textureFor(model, texture_slot, error);
      if (state.textures[static_cast<size_t>(slot)] == nullptr) return false;
    }
    // GLES2 guarantees 8 texture units: the diffuse map, up to three
    // specular rungs and the BRDF table take 5 at worst. Textures beyond the
    // GPU's units are left out, the least visible first.
    const int units_left = capabilities.max_fragment_texture_units - 5;
    int used = 0;
    for (const auto* texture : state.textures) used += texture != nullptr ? 1 : 0;
    for (int slot : {kEmissive, kOcclusion, kNormal, kMetallicRoughness}) {
      if (used <= units_left) break;
      if (state.textures[static_cast<size_t>(slot)] == nullptr) continue;
      state.textures[static_cast<size_t>(slot)] = nullptr;
      --used;
      warnings_.push_back("material \"" + material.name + "\": its " + kSlotNames[slot] +
                          " texture is left out (the GPU has " +
                          std::to_string(capabilities.max_fragment_texture_units) + " texture units)");
    }
    materials_.push_back(state);
  }

  for (const model::Primitive& primitive : model.primitives) {
    const std::size_t material = primitive.material >= 0 && primitive.material < static_cast<int>(model.materials.size())
                                     ? static_cast<std::size_t>(primitive.material)
                                     : materials_.size() - 1;
    if (!uploadPrimitive(primitive, material, world_from_model, error)) return false;
    stats_.triangles += primitive.triangleCount();
  }
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  stats_.draw_pieces = pieces_.size();
  stats_.textures = textures_.size();
  // Every piece's program with the mirror-only ladder now, so a shader that
  // does not build fails here, not mid-run.
  for (const Piece& piece : pieces_)
    if (programFor(piece, 0, 0, 0, 0, 0, false, false, false, error) == nullptr) return false;
  stats_.upload_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return gles::checkGl("ModelRenderer::init", error);
}

const gles::Texture* ModelRenderer::textureFor(const model::MeshModel& model, const model::TextureSlot& slot,
                                               std::string& error) {
  if (slot.image < 0 || slot.image >= static_cast<int>(model.images.size())) {
    error = "ModelRenderer: texture slot names image " + std::to_string(slot.image) + ", which the model lacks";
    return nullptr;
  }
  const auto key = std::make_tuple(slot.image, static_cast<int>(slot.wrap_s), static_cast<int>(slot.wrap_t), 0,
                                   slot.nearest);
  if (auto found = textures_.find(key); found != textures_.end()) return &found->second;
  const model::TextureImage& image = model.images[static_cast<size_t>(slot.image)];
  if (image.width <= 0 || image.height <= 0 ||
      image.rgba.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 4) {
    error = "ModelRenderer: image \"" + image.name + "\" has no pixels";
    return nullptr;
  }
  const int limit = std::min(settings_.max_texture_size_px, std::max(capabilities_.max_texture_size_px, 1));
  const bool npot = capabilities_.texture_npot && !settings_.force_power_of_two;
  int width = image.width, height = image.height;
  if (!npot) {
    width = nearestPowerOfTwo(width, limit);
    height = nearestPowerOfTwo(height, limit);
  } else if (std::max(width, height) > limit) {
    const double shrink = static_cast<double>(limit) / std::max(width, height);
    width = std::max(1, static_cast<int>(std::lround(width * shrink)));
    height = std::max(1, static_cast<int>(std::lround(height * shrink)));
  }
  cv::Mat pixels(image.height, image.width, CV_8UC4, const_cast<std::uint8_t*>(image.rgba.data()));
  cv::Mat resized;
  if (width != image.width || height != image.height) {
    cv::resize(pixels, resized, cv::Size(width, height), 0, 0,
               width < image.width || height < image.height ? cv::INTER_AREA : cv::INTER_LINEAR);
    warnings_.push_back("image \"" + image.name + "\" is resized from " + std::to_string(image.width) + "x" +
                        std::to_string(image.height) + " to " + std::to_string(width) + "x" +
                        std::to_string(height) + (npot ? " (the texture size limit)" : " (GLES2 mipmaps need powers of two)"));
  } else {
    resized = pixels;
  }
  gles::Texture texture = gles::Texture::create();
  glBindTexture(GL_TEXTURE_2D, texture.id());
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, resized.data);
  glGenerateMipmap(GL_TEXTURE_2D);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, slot.nearest ? GL_NEAREST : GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, glWrap(slot.wrap_s));
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, glWrap(slot.wrap_t));
  glBindTexture(GL_TEXTURE_2D, 0);
  if (!gles::checkGl("ModelRenderer texture upload", error)) return nullptr;
  stats_.texture_bytes += mipChainBytes(width, height);
  return &textures_.emplace(key, std::move(texture)).first->second;
}

bool ModelRenderer::uploadPrimitive(const model::Primitive& source, std::size_t material,
                                    const glm::dmat4& world_from_model, std::string& error) {
  const MaterialState& state = materials_[material];
  const model::Primitive primitive = source.normals.empty() ? model::withFlatNormals(source) : source;
  const std::size_t count = primitive.positions_m.size();

  PieceFormat layout;
  layout.material = material;
  bool needs_uv[2] = {false, false};
  for (int slot = 0; slot < kSlotCount; ++slot) {
    if (state.textures[static_cast<size_t>(slot)] == nullptr) continue;
    const int set = slotOf(state.material, slot).texcoord == 1 ? 1 : 0;
    const std::vector<glm::vec2>& uv = set == 1 ? primitive.uv1 : primitive.uv0;
    if (uv.size() != count) {
      warnings_.push_back(std::string("material \"") + state.material.name + "\": its " + kSlotNames[slot] +
                          " texture is left out on a primitive without TEXCOORD_" + std::to_string(set));
      continue;
    }
    layout.slot_used[static_cast<size_t>(slot)] = true;
    needs_uv[set] = true;
  }
  const bool has_tangent = layout.slot_used[kNormal];
  std::vector<glm::vec4> tangents = primitive.tangents;
  if (has_tangent && tangents.size() != count) {
    const int set = state.material.normal.texcoord == 1 ? 1 : 0;
    tangents = model::tangentsFromUvs(primitive.positions_m, primitive.normals, set == 1 ? primitive.uv1 : primitive.uv0,
                                      primitive.indices);
  }
  const bool has_color = primitive.colors.size() == count;
  int floats = 6;
  if (has_tangent) layout.tangent_offset = floats * 4, floats += 4;
  if (needs_uv[0]) layout.uv0_offset = floats * 4, floats += 2;
  if (needs_uv[1]) layout.uv1_offset = floats * 4, floats += 2;
  if (has_color) layout.color_offset = floats * 4, floats += 4;
  layout.stride_bytes = floats * 4;

  // Defines: everything about this piece but the ladder's span.
  std::string defines;
  if (has_tangent) defines += "#define HAS_TANGENT\n";
  if (needs_uv[0]) defines += "#define HAS_UV0\n";
  if (needs_uv[1]) defines += "#define HAS_UV1\n";
  if (has_color) defines += "#define HAS_COLOR\n";
  for (int slot = 0; slot < kSlotCount; ++slot) {
    if (!layout.slot_used[static_cast<size_t>(slot)]) continue;
    defines += std::string("#define ") + kSlotDefines[slot] + "_TEXTURE\n#define " + kSlotDefines[slot] + "_UV " +
               (slotOf(state.material, slot).texcoord == 1 ? "v_uv1" : "v_uv0") + "\n";
  }
  if (state.material.alpha_mode == model::AlphaMode::kMask) defines += "#define ALPHA_MASK\n";
  if (state.material.alpha_mode == model::AlphaMode::kBlend) defines += "#define ALPHA_BLEND\n";
  if (state.material.double_sided) defines += "#define DOUBLE_SIDED\n";
  layout.defines = defines;

  // Vertices in W. Normals by the inverse transpose (the placement's scale
  // is uniform, but a node's own may not be: the loader has applied those
  // already, so this one is a turn and a scale).
  const glm::dmat3 normal_from_model = glm::transpose(glm::inverse(glm::dmat3(world_from_model)));
  const glm::dmat3 direction_from_model(world_from_model);
  std::vector<float> vertices(count * static_cast<std::size_t>(floats));
  glm::dvec3 centre(0.0);
  for (std::size_t i = 0; i < count; ++i) {
    float* v = &vertices[i * static_cast<std::size_t>(floats)];
    const glm::dvec3 p = glm::dvec3(world_from_model * glm::dvec4(glm::dvec3(primitive.positions_m[i]), 1.0));
    centre += p;
    bounds_min_w_ = glm::min(bounds_min_w_, p);
    bounds_max_w_ = glm::max(bounds_max_w_, p);
    glm::dvec3 n = normal_from_model * glm::dvec3(primitive.normals[i]);
    const double length = glm::length(n);
    n = length > 0.0 && std::isfinite(length) ? n / length : glm::dvec3(0, 0, 1);
    v[0] = static_cast<float>(p.x), v[1] = static_cast<float>(p.y), v[2] = static_cast<float>(p.z);
    v[3] = static_cast<float>(n.x), v[4] = static_cast<float>(n.y), v[5] = static_cast<float>(n.z);
    if (layout.tangent_offset >= 0) {
      const glm::dvec3 t = direction_from_model * glm::dvec3(glm::vec3(tangents[i]));
      float* out = v + layout.tangent_offset / 4;
      out[0] = static_cast<float>(t.x), out[1] = static_cast<float>(t.y), out[2] = static_cast<float>(t.z);
      // A mirroring placement would flip handedness; this one (turn, positive scale) does not.
      out[3] = tangents[i].w < 0.0f ? -1.0f : 1.0f;
    }
    if (layout.uv0_offset >= 0) std::copy_n(glm::value_ptr(primitive.uv0[i]), 2, v + layout.uv0_offset / 4);
    if (layout.uv1_offset >= 0) std::copy_n(glm::value_ptr(primitive.uv1[i]), 2, v + layout.uv1_offset / 4);
    if (layout.color_offset >= 0) std::copy_n(glm::value_ptr(primitive.colors[i]), 4, v + layout.color_offset / 4);
  }
  layout.centre_w = count > 0 ? glm::vec3(centre / static_cast<double>(count)) : glm::vec3(0.0f);

  const bool uint_indices = capabilities_.element_index_uint && !settings_.force_short_indices;
  auto addPiece = [&](const float* piece_vertices, std::size_t piece_vertex_count, const void* indices,
                      std::size_t index_count, GLenum index_type) {
    Piece piece;
    static_cast<PieceFormat&>(piece) = layout;
    piece.vertices = gles::Buffer::create();
    glBindBuffer(GL_ARRAY_BUFFER, piece.vertices.id());
    const auto vertex_bytes = static_cast<GLsizeiptr>(piece_vertex_count * static_cast<std::size_t>(layout.stride_bytes));
    glBufferData(GL_ARRAY_BUFFER, vertex_bytes, piece_vertices, GL_STATIC_DRAW);
    piece.indices = gles::Buffer::create();
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, piece.indices.id());
    const std::size_t index_size = index_type == GL_UNSIGNED_INT ? 4 : 2;
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(index_count * index_size), indices, GL_STATIC_DRAW);
    piece.index_count = static_cast<GLsizei>(index_count);
    piece.index_type = index_type;
    stats_.vertex_bytes += static_cast<std::uint64_t>(vertex_bytes);
    stats_.index_bytes += index_count * index_size;
    pieces_.push_back(std::move(piece));
  };
  const std::size_t corners = primitive.indices.size() / 3 * 3;
  if (corners == 0) return true;
  if (count <= 65536) {
    std::vector<std::uint16_t> indices(primitive.indices.begin(), primitive.indices.begin() + static_cast<long>(corners));
    addPiece(vertices.data(), count, indices.data(), corners, GL_UNSIGNED_SHORT);
  } else if (uint_indices) {
    stats_.short_indices_only = false;
    addPiece(vertices.data(), count, primitive.indices.data(), corners, GL_UNSIGNED_INT);
  } else {
    const std::vector<model::ShortIndexPiece> split = model::splitForShortIndices(
        std::vector<std::uint32_t>(primitive.indices.begin(), primitive.indices.begin() + static_cast<long>(corners)));
    for (const model::ShortIndexPiece& part : split) {
      std::vector<float> part_vertices(part.vertices.size() * static_cast<std::size_t>(floats));
      for (std::size_t k = 0; k < part.vertices.size(); ++k)
        std::copy_n(&vertices[part.vertices[k] * static_cast<std::size_t>(floats)], floats,
                    &part_vertices[k * static_cast<std::size_t>(floats)]);
      addPiece(part_vertices.data(), part.vertices.size(), part.indices.data(), part.indices.size(), GL_UNSIGNED_SHORT);
    }
    stats_.split_pieces += split.size();
  }
  return gles::checkGl("ModelRenderer upload", error);
}

const gles::Program* ModelRenderer::programFor(const Piece& piece, int rung_first, int rung_last, int glossy_levels,
                                               int self_shadow_lights, int self_shadow_floor, bool floor_shadow,
                                               bool floor_camera, bool noise_in_shader, std::string& error) {
  std::string defines = cubeStorageDefines(storage_) +
                        cameraResponseDefines(settings_.camera_transfer, noise_in_shader) +
                        (bloom_bright_pass_ ? bloomBrightPassDefines() : std::string()) + piece.defines +
                        "#define GLOSSY_LEVELS " +
                        std::to_string(glossy_levels) + "\n#define RUNG_FIRST " + std::to_string(rung_first) +
                        "\n#define RUNG_LAST " + std::to_string(rung_last) + "\n";
  if (self_shadow_lights > 0) {
    defines += "#define SELF_SHADOW_LIGHTS " + std::to_string(self_shadow_lights) + "\n";
    if (self_shadow_packed_) defines += "#define SHADOW_DEPTH_PACKED\n";
    if (self_shadow_floor > 0) defines += "#define SELF_SHADOW_FLOOR_LIGHTS " + std::to_string(self_shadow_floor) + "\n";
  }
  if (near_floor_.enabled) {
    defines += "#define NEAR_FLOOR\n#define NEAR_FLOOR_MAX_DISTANCE_M " + std::to_string(ibl::kNearFloorMaxDistance_m) +
               "\n#define NEAR_FLOOR_BALL_STEPS " + std::to_string(ibl::kNearFloorBallSteps) + "\n";
    if (floor_shadow) defines += "#define NEAR_FLOOR_SHADOW\n";
    if (floor_camera) {
      defines += "#define NEAR_FLOOR_CAMERA\n#define CAMERA_FLOOR_MARGIN_PX " + std::to_string(ibl::kCameraFloorMarginPx) + "\n";
    }
  }
  if (auto found = programs_.find(defines); found != programs_.end()) return &found->second;
  auto program = gles::Program::fromEmbedded("model_object.vert", "model_object.frag", defines, error);
  if (!program) return nullptr;
  return &programs_.emplace(defines, std::move(*program)).first->second;
}

bool ModelRenderer::prepareEdges(int width_px, int height_px, int target_samples, std::string& error) {
  const EdgeAntialiasing request =
      chooseEdgeAntialiasing(capabilities_, settings_.edge_samples, target_samples, width_px, height_px);
  if (request == edge_request_ && width_px == edge_width_px_ && height_px == edge_height_px_) return true;
  edge_request_ = request;
  edge_width_px_ = width_px;
  edge_height_px_ = height_px;
  EdgeAntialiasing choice = request;
  stats_.edge_layer_bytes = 0;
  if (choice.usesLayer()) {
    std::string why;
    bool made = edge_layer_.init(capabilities_, choice, width_px, height_px, why);
    if (!made && choice.strategy == EdgeStrategy::kMultisampleRenderToTexture) {
      // A driver that lists the EXT and then refuses the framebuffer: the
      // core path, which needs nothing optional.
      warnings_.push_back("edge anti-aliasing: " + why + "; using the supersampled layer instead");
      gles::Capabilities without = capabilities_;
      without.multisampled_render_to_texture = false;
      choice = chooseEdgeAntialiasing(without, settings_.edge_samples, target_samples, width_px, height_px);
      made = choice.usesLayer() && edge_layer_.init(capabilities_, choice, width_px, height_px, why);
    }
    if (!made) {
      if (choice.usesLayer()) warnings_.push_back("edge anti-aliasing: " + why + "; edges are not smoothed");
      const int requested = choice.requested_samples;
      choice = EdgeAntialiasing{};
      choice.requested_samples = requested;
      choice.reason = "the GPU refused the layer: " + why;
      edge_layer_ = EdgeLayer{};
      // The failed allocation's GL error is spent; the frame goes on without.
      while (glGetError() != GL_NO_ERROR) {
      }
    } else {
      choice.samples = edge_layer_.samples();
      stats_.edge_layer_bytes = edge_layer_.bytes();
    }
  } else {
    edge_layer_ = EdgeLayer{};
  }
  stats_.edges = choice;
  return gles::checkGl("ModelRenderer::prepareEdges", error);
}

void ModelRenderer::setNearFloor(const NearFloor& near_floor) { near_floor_ = near_floor; }

void ModelRenderer::setSelfShadow(const std::vector<SelfShadowLight>* lights, int map_size_px, bool packed_depth,
                                  const std::vector<SelfShadowLight>* floor) {
  self_shadow_ = lights;
  self_shadow_floor_ = floor;
  self_shadow_map_size_px_ = map_size_px;
  self_shadow_packed_ = packed_depth;
}

bool ModelRenderer::draw(const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                         const ibl::SceneLighting& lighting, EnvironmentMaps& environment, std::string& error) {
  if (environment.storage() != storage_) {
    error = "ModelRenderer: initialised for a different cube map storage than these EnvironmentMaps use";
    return false;
  }
  if (sensor_noise_ != nullptr && !bloom_bright_pass_ && !noise_texture_.valid() && !noise_texture_.init(error))
    return false;
  dome_rgb_scale_ = lighting.dome_rgb_scale;
  const int glossy_levels = environment.glossyWritten() ? std::clamp(environment.glossyLevels(), 0, 2) : 0;
  std::vector<double> exponents;
  for (int level = 0; level < glossy_levels; ++level)
    exponents.push_back(environment.settings().glossy_exponent[static_cast<size_t>(level)]);
  const std::vector<double> rung_alphas = ibl::specularRungAlphas(exponents);


  std::vector<const Piece*> opaque, blended;
  for (const Piece& piece : pieces_)
    (materials_[piece.material].material.alpha_mode == model::AlphaMode::kBlend ? blended : opaque).push_back(&piece);
  const glm::vec3 eye_w(pose.cameraCenterWorld());
  std::stable_sort(blended.begin(), blended.end(), [&](const Piece* a, const Piece* b) {
    return glm::length(a->centre_w - eye_w) > glm::length(b->centre_w - eye_w);
  });

  // The framebuffer's own samples decide first (kMultisampleConfig): a
  // multisampled target needs no layer. The bloom's bright pass is drawn
  // straight into its own target (its light is blurred far beyond an edge).
  bool layered = false;
  if (!bloom_bright_pass_) {
    GLint target_samples = 0;
    glGetIntegerv(GL_SAMPLES, &target_samples);
    if (!prepareEdges(camera.width_px, camera.height_px, target_samples, error)) return false;
    layered = stats_.edges.usesLayer();
  }
  if (layered) {
    // 2 px of margin: the GPU's fp32 projection against the CPU's double,
    // and the bow of the distorted outline between its samples.
    const PixelRect region =
        projectedBounds(camera, pose, bounds_min_w_, bounds_max_w_, settings_.near_m, /*margin_px=*/2);
    if (region.empty() || pieces_.empty()) return true;  // nothing of the model is in the frame
    edge_layer_.begin(region);
  }

  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
  glFrontFace(GL_CCW);
  glCullFace(GL_BACK);
  for (const Piece* piece : opaque)
    if (!drawPiece(*piece, camera, pose, lighting, environment, rung_alphas, error)) {
      if (layered) edge_layer_.restore();
      return false;
    }
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  if (layered) {
    // The layer holds premultiplied colour over transparent black: colour
    // a c + (1 - a) dst as before, and alpha a + (1 - a) dst_a (the layer's
    // coverage), so that layer + (1 - alpha) video is this blend over the video.
    glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  } else {
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  }
  for (const Piece* piece : blended)
    if (!drawPiece(*piece, camera, pose, lighting, environment, rung_alphas, error)) {
      if (layered) edge_layer_.restore();
      return false;
    }
  glDisable(GL_BLEND);
  glDepthMask(GL_TRUE);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  if (layered && !edge_layer_.composite(error, sensor_noise_, &noise_texture_)) return false;
  glActiveTexture(GL_TEXTURE0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  return gles::checkGl("ModelRenderer::draw", error);
}

void ModelRenderer::bindSelfShadowLights(const gles::Program& program, const std::string& prefix,
                                         const std::vector<SelfShadowLight>& lights, int count, int& unit) const {
  std::vector<GLint> units;
  std::vector<glm::vec4> row0, row1, row2;
  std::vector<glm::vec3> directions, rgb;
  std::vector<glm::vec2> texels;
  for (int i = 0; i < count; ++i) {
    const SelfShadowLight& light = lights[static_cast<size_t>(i)];
    glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(unit));
    glBindTexture(GL_TEXTURE_2D, light.map);
    units.push_back(unit++);
    // uv = 0.5 clip.xy + 0.5 and depth01 = 0.5 clip.z + 0.5 (orthographic: w = 1).
    const glm::mat4 m = light.clip_from_world;
    auto row = [&](int r) { return glm::vec4(m[0][r], m[1][r], m[2][r], m[3][r]); };
    const glm::vec4 half_w(0.0f, 0.0f, 0.0f, 0.5f);
    row0.push_back(0.5f * row(0) + half_w);
    row1.push_back(0.5f * row(1) + half_w);
    row2.push_back(0.5f * row(2) + half_w);
    directions.push_back(light.direction_w);
    rgb.push_back(light.rgb * dome_rgb_scale_);
    const float texel_uv = 1.0f / static_cast<float>(self_shadow_map_size_px_);
    texels.emplace_back(texel_uv, light.depth_range_m > 0.0f ? light.width_m * texel_uv / light.depth_range_m : 0.0f);
  }
  // Names the program lacks (the floor's lights have no rgb) are location
  // -1, which GL ignores.
  auto name = [&](const char* suffix) { return prefix + suffix; };
  glUniform1iv(program.uniform(name("_map").c_str()), count, units.data());
  glUniform4fv(program.uniform(name("_row0").c_str()), count, glm::value_ptr(row0[0]));
  glUniform4fv(program.uniform(name("_row1").c_str()), count, glm::value_ptr(row1[0]));
  glUniform4fv(program.uniform(name("_row2").c_str()), count, glm::value_ptr(row2[0]));
  glUniform3fv(program.uniform(name("_direction").c_str()), count, glm::value_ptr(directions[0]));
  glUniform3fv(program.uniform(name("_rgb").c_str()), count, glm::value_ptr(rgb[0]));
  glUniform2fv(program.uniform(name("_texel").c_str()), count, glm::value_ptr(texels[0]));
}

bool ModelRenderer::drawPiece(const Piece& piece, const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                              const ibl::SceneLighting& lighting, EnvironmentMaps& environment,
                              const std::vector<double>& rung_alphas, std::string& error) {
  const MaterialState& state = materials_[piece.material];
  const model::Material& material = state.material;
  const ibl::RungRange range = ibl::specularRungRange(state.min_roughness, state.max_roughness, rung_alphas);
  const int glossy_levels = static_cast<int>(rung_alphas.size()) - 2;
  // Self-shadow lights: what the units left (diffuse, the rungs, the BRDF
  // table and the textures come first) and the fragment uniforms allow
  // (6 vectors a light; the rest of the shader uses under 48, and the
  // frame's noise 5 more).
  int units_used = 2;  // the diffuse map and the BRDF table
  for (int rung = range.first; rung <= range.last; ++rung) units_used += rung < glossy_levels + 1 ? 1 : 0;
  for (bool used : piece.slot_used) units_used += used ? 1 : 0;
  // The frame's noise, before the self-shadow lights: it is the whole
  // model's grain, against one of eight lights' shadows.
  const bool noise_in_shader = !bloom_bright_pass_ && sensor_noise_ != nullptr && noise_texture_.valid() &&
                               !(stats_.edges.usesLayer() && edge_layer_.addsNoiseAfterResolve()) &&
                               units_used < capabilities_.max_fragment_texture_units;
  units_used += noise_in_shader ? 1 : 0;
  const int base_uniform_vectors = 48 + (noise_in_shader ? 5 : 0);
  // The floor's shadow and the camera's view of it in the reflections
  // before the self-shadow lights: a unit each, against one of eight lights.
  const bool floor_shadow = near_floor_.enabled && near_floor_.shadow != nullptr && near_floor_.shadow->hasShadow() &&
                            units_used < capabilities_.max_fragment_texture_units;
  units_used += floor_shadow ? 1 : 0;
  const bool floor_camera = near_floor_.enabled && near_floor_.camera_frame != nullptr && range.first == 0 &&
                            units_used < capabilities_.max_fragment_texture_units;
  units_used += floor_camera ? 1 : 0;
  // The floor's light hidden by the model itself: a unit and 5 vectors a
  // direction, all or none, with at least one dome light left beside them
  // (without the dome there is no self-shadow to speak of).
  int self_shadow_floor = 0;
  if (self_shadow_ != nullptr && !self_shadow_->empty() && self_shadow_map_size_px_ > 0 &&
      self_shadow_floor_ != nullptr && !self_shadow_floor_->empty()) {
    const int wanted = static_cast<int>(self_shadow_floor_->size());
    if (units_used + wanted < capabilities_.max_fragment_texture_units &&
        base_uniform_vectors + 5 * wanted + 6 <= capabilities_.max_fragment_uniform_vectors)
      self_shadow_floor = wanted;
  }
  units_used += self_shadow_floor;
  int self_shadow_lights = 0;
  if (self_shadow_ != nullptr && self_shadow_map_size_px_ > 0)
    self_shadow_lights = std::max(0, std::min({static_cast<int>(self_shadow_->size()),
                                               capabilities_.max_fragment_texture_units - units_used,
                                               (capabilities_.max_fragment_uniform_vectors - base_uniform_vectors -
                                                5 * self_shadow_floor) / 6}));
  self_shadow_lights_read_ = self_shadow_lights;
  const gles::Program* found =
      programFor(piece, range.first, range.last, glossy_levels, self_shadow_lights,
                 self_shadow_lights > 0 ? self_shadow_floor : 0, floor_shadow, floor_camera, noise_in_shader, error);
  if (found == nullptr) return false;
  const gles::Program& program = *found;
  program.use();
  setCameraProjectionUniforms(program, camera, pose, settings_.near_m, settings_.far_m);

  int unit = kDiffuseUnit;
  bindCubeMapUniforms(program, "u_diffuse", environment.diffuse(), unit++);
  if (range.first == 0) bindCubeMapUniforms(program, "u_reflection", environment.reflection(), unit++);
  for (int level = 0; level < glossy_levels; ++level)
    if (range.first <= level + 1 && range.last >= level + 1)
      bindCubeMapUniforms(program, "u_glossy" + std::to_string(level), environment.glossy(level), unit++);
  float alphas[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  for (std::size_t k = 0; k < rung_alphas.size() && k < 4; ++k) alphas[k] = static_cast<float>(rung_alphas[k]);
  glUniform1fv(program.uniform("u_rung_alpha"), 4, alphas);
  glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(unit));
  glBindTexture(GL_TEXTURE_2D, brdf_table_.id());
  glUniform1i(program.uniform("u_brdf_table"), unit++);
  glUniform1f(program.uniform("u_brdf_table_size"), static_cast<float>(brdf_table_size_));
  setCameraResponseUniforms(program, settings_.camera_transfer, response_gain_rgb_,
                            noise_in_shader ? sensor_noise_ : nullptr, noise_texture_, unit);
  unit += noise_in_shader ? 1 : 0;
  for (int slot = 0; slot < kSlotCount; ++slot) {
    if (!piece.slot_used[static_cast<size_t>(slot)]) continue;
    const std::string prefix = kSlotUniforms[slot];
    glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(unit));
    glBindTexture(GL_TEXTURE_2D, state.textures[static_cast<size_t>(slot)]->id());
    glUniform1i(program.uniform((prefix + "_texture").c_str()), unit++);
    const glm::mat3 transform = textureTransformMatrix(slotOf(material, slot));
    glUniformMatrix3fv(program.uniform((prefix + "_uv_transform").c_str()), 1, GL_FALSE, glm::value_ptr(transform));
  }
  if (self_shadow_lights > 0) {
    bindSelfShadowLights(program, "u_self_shadow", *self_shadow_, self_shadow_lights, unit);
    if (self_shadow_floor > 0)
      bindSelfShadowLights(program, "u_self_shadow_floor", *self_shadow_floor_, self_shadow_floor, unit);
  }
  if (near_floor_.enabled) {
    glUniform3fv(program.uniform("u_ball_centre_w"), 1, glm::value_ptr(glm::vec3(near_floor_.ball_centre_w)));
    glUniform1f(program.uniform("u_ball_radius_m"), static_cast<float>(near_floor_.ball_radius_m));
    // The camera that sees the ball now: the one the maps were last made
    // from, give or take a steady camera's drift (maps_stage remakes them
    // only for a steady view).
    const glm::dvec3 to_eye = pose.cameraCenterWorld() - near_floor_.ball_centre_w;
    const double to_eye_length = glm::length(to_eye);
    const glm::vec3 to_eye_w = to_eye_length > 0.0 ? glm::vec3(to_eye / to_eye_length) : glm::vec3(0.0f, 0.0f, 1.0f);
    glUniform3fv(program.uniform("u_ball_to_eye_w"), 1, glm::value_ptr(to_eye_w));
    if (floor_camera) {
      glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(unit));
      glBindTexture(GL_TEXTURE_2D, near_floor_.camera_frame->texture());
      glUniform1i(program.uniform("u_floor_camera"), unit++);
      // The frame's pixels into the units of the maps beside them (the
      // inverse of the gain the object leaves with).
      const glm::vec3 frame_to_maps = 1.0f / glm::max(response_gain_rgb_, glm::vec3(1e-6f));
      glUniform3fv(program.uniform("u_floor_camera_to_maps"), 1, glm::value_ptr(frame_to_maps));
      const glm::mat3 rotation(pose.R_cam_from_world);
      glUniformMatrix3fv(program.uniform("u_floor_rotation_cam_from_world"), 1, GL_FALSE, glm::value_ptr(rotation));
      glUniform3fv(program.uniform("u_floor_translation_cam_from_world"), 1,
                   glm::value_ptr(glm::vec3(pose.t_cam_from_world)));
      glUniform4f(program.uniform("u_floor_distortion"), static_cast<float>(camera.distortion[0]),
                  static_cast<float>(camera.distortion[1]), static_cast<float>(camera.distortion[2]),
                  static_cast<float>(camera.distortion[3]));
      glUniform1f(program.uniform("u_floor_distortion_k3"), static_cast<float>(camera.distortion[4]));
      glUniform2f(program.uniform("u_floor_focal_px"), static_cast<float>(camera.fx_px), static_cast<float>(camera.fy_px));
      glUniform2f(program.uniform("u_floor_principal_px"), static_cast<float>(camera.cx_px),
                  static_cast<float>(camera.cy_px));
      glUniform2f(program.uniform("u_floor_image_size_px"), static_cast<float>(camera.width_px),
                  static_cast<float>(camera.height_px));
      glUniform1f(program.uniform("u_floor_reach2"), static_cast<float>(ibl::cameraFloorReach2(camera)));
    }
    if (floor_shadow) {
      const ibl::GroundRegion& region = near_floor_.shadow->region();
      glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(unit));
      glBindTexture(GL_TEXTURE_2D, near_floor_.shadow->fractionTexture());
      glUniform1i(program.uniform("u_ground_fraction"), unit++);
      glUniform3f(program.uniform("u_ground_region"), static_cast<float>(region.centre_w.x),
                  static_cast<float>(region.centre_w.y), static_cast<float>(0.5 / region.half_size_m));
    }
  }
  glActiveTexture(GL_TEXTURE0);

  glUniform4fv(program.uniform("u_base_color_factor"), 1, glm::value_ptr(material.base_color_factor));
  glUniform1f(program.uniform("u_metallic_factor"), material.metallic_factor);
  glUniform1f(program.uniform("u_roughness_factor"), material.roughness_factor);
  glUniform3fv(program.uniform("u_emissive_factor"), 1, glm::value_ptr(material.emissive_factor));
  glUniform1f(program.uniform("u_normal_scale"), material.normal_scale);
  glUniform1f(program.uniform("u_occlusion_strength"), material.occlusion_strength);
  glUniform1f(program.uniform("u_alpha_cutoff"), material.alpha_cutoff);
  glUniform3fv(program.uniform("u_clipped_direction_w"), ibl::SceneLighting::kMaxClippedLights,
               glm::value_ptr(lighting.clipped_direction_w[0]));
  glUniform3fv(program.uniform("u_clipped_diffuse_rgb"), ibl::SceneLighting::kMaxClippedLights,
               glm::value_ptr(lighting.clipped_diffuse_rgb[0]));
  glUniform3fv(program.uniform("u_lamp_direction_w"), 1, glm::value_ptr(lighting.lamp_direction_w));
  glUniform3fv(program.uniform("u_lamp_diffuse_rgb"), 1, glm::value_ptr(lighting.lamp_diffuse_rgb));

  if (material.double_sided)
    glDisable(GL_CULL_FACE);
  else
    glEnable(GL_CULL_FACE);

  glBindBuffer(GL_ARRAY_BUFFER, piece.vertices.id());
  std::vector<GLuint> enabled;
  auto attribute = [&](const char* name, int size, int offset) {
    if (offset < 0) return;
    const GLint location = program.attribute(name);
    if (location < 0) return;  // compiled out
    glEnableVertexAttribArray(static_cast<GLuint>(location));
    glVertexAttribPointer(static_cast<GLuint>(location), size, GL_FLOAT, GL_FALSE, piece.stride_bytes,
                          reinterpret_cast<const void*>(static_cast<std::uintptr_t>(offset)));
    enabled.push_back(static_cast<GLuint>(location));
  };
  attribute("a_position_w", 3, 0);
  attribute("a_normal_w", 3, 12);
  attribute("a_tangent_w", 4, piece.tangent_offset);
  attribute("a_uv0", 2, piece.uv0_offset);
  attribute("a_uv1", 2, piece.uv1_offset);
  attribute("a_color", 4, piece.color_offset);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, piece.indices.id());
  glDrawElements(GL_TRIANGLES, piece.index_count, piece.index_type, nullptr);
  for (GLuint location : enabled) glDisableVertexAttribArray(location);
  return true;
}

}  // namespace probelight::passes
