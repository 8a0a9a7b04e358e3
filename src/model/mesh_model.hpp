// A user's model as the renderer and the simulator take it: triangles in
// the model's own frame (metres, Z up, as the world frame), the glTF
// metallic-roughness materials and their texture images. Pure data, no GL:
// model/gltf_loader.hpp makes one from a .gltf or .glb file, and the node
// hierarchy is already flattened into it (each mesh instance has its
// vertices in the model frame).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace probelight::model {

enum class AlphaMode { kOpaque, kMask, kBlend };

// glTF's sampler wrap modes (the GL enums' meaning).
enum class TextureWrap { kRepeat, kClampToEdge, kMirroredRepeat };

// One texture slot of a material: which image, which UV set, how it is
// sampled, and KHR_texture_transform's offset, rotation and scale
// (uv' = T * R * S * uv, the extension's order).
struct TextureSlot {
  int image = -1;    // into MeshModel::images; -1: no texture
  int texcoord = 0;  // TEXCOORD_0 or TEXCOORD_1
  TextureWrap wrap_s = TextureWrap::kRepeat, wrap_t = TextureWrap::kRepeat;
  bool nearest = false;  // magFilter NEAREST (pixel art); linear otherwise
  glm::vec2 uv_offset{0.0f}, uv_scale{1.0f};
  float uv_rotation_rad = 0.0f;
  bool present() const { return image >= 0; }
};

// The glTF 2.0 metallic-roughness material, factors and textures as the
// file gives them (base colour factor linear, base colour texture sRGB).
struct Material {
  std::string name;
  glm::vec4 base_color_factor{1.0f};
  TextureSlot base_color;
  float metallic_factor = 1.0f, roughness_factor = 1.0f;
  TextureSlot metallic_roughness;  // roughness in G, metallic in B
  TextureSlot normal;
  float normal_scale = 1.0f;
  TextureSlot occlusion;  // in R
  float occlusion_strength = 1.0f;
  glm::vec3 emissive_factor{0.0f};
  TextureSlot emissive;
  AlphaMode alpha_mode = AlphaMode::kOpaque;
  float alpha_cutoff = 0.5f;
  bool double_sided = false;
};

// A decoded texture image, RGBA8, rows top first (as the file stores them).
struct TextureImage {
  std::string name;  // its uri, or "image N"
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;
};

// Triangles of one material. Every attribute array has one entry per
// vertex, or is empty where the file has none (then normals are made flat
// and tangents from the UVs by whoever draws). Indices are always there:
// a non-indexed primitive gets 0, 1, 2, ...
struct Primitive {
  std::vector<glm::vec3> positions_m;
  std::vector<glm::vec3> normals;
  std::vector<glm::vec4> tangents;  // xyz, w = handedness (+1 or -1)
  std::vector<glm::vec2> uv0, uv1;
  std::vector<glm::vec4> colors;  // COLOR_0, linear RGBA
  std::vector<std::uint32_t> indices;
  int material = -1;  // into MeshModel::materials; -1: glTF's default material
  std::size_t triangleCount() const { return indices.size() / 3; }
};

struct MeshModel {
  std::string source;  // the file it came from
  std::vector<Primitive> primitives;
  std::vector<Material> materials;
  std::vector<TextureImage> images;
  glm::vec3 min_m{0.0f}, max_m{0.0f};  // bounds in the model frame (Z up)
  std::vector<std::string> warnings;  // one line each, said once at load
  double load_ms = 0.0;

  std::size_t triangleCount() const;
  std::size_t vertexCount() const;
  // What it holds in memory: vertex and index arrays and decoded images.
  std::uint64_t bytes() const;
  // The largest index any primitive uses: above 65535 a GLES2 board needs
  // OES_element_index_uint.
  std::uint32_t maxIndex() const;
};

}  // namespace probelight::model
