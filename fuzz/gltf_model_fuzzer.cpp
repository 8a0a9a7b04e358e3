// A user's model (loadGltfModel, as `object.model` will read it): a .gltf
// or .glb is one line of error naming the file and the field, or a model
// whose every number the renderer may trust.
#include <cmath>

#include "fuzz/fuzz_input.hpp"
#include "model/gltf_loader.hpp"

using namespace probelight;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The loader tells .glb from .gltf by the bytes, not the name.
  const std::string path = fuzz::writeInput(data, size, "model.gltf");
  model::ModelLimits limits;
  limits.max_model_bytes = 64ull << 20;  // libFuzzer's -rss_limit_mb is 2 GB
  model::MeshModel loaded;
  std::string error;
  if (!model::loadGltfModel(path, limits, loaded, error)) {
    fuzz::requireOneLineNaming(error, path);
    fuzz::require(loaded.primitives.empty(), "a refused model left primitives behind");
    return 0;
  }
  fuzz::require(loaded.bytes() <= limits.max_model_bytes + (1u << 20), "a model above the size limit loaded");
  for (const model::Primitive& p : loaded.primitives) {
    fuzz::require(p.indices.size() % 3 == 0 && !p.indices.empty(), "a primitive that is not whole triangles");
    for (const std::uint32_t index : p.indices) fuzz::require(index < p.positions_m.size(), "an index past the vertices");
    for (const glm::vec3& v : p.positions_m)
      fuzz::require(fuzz::finite(v.x) && fuzz::finite(v.y) && fuzz::finite(v.z), "a vertex that is not finite");
    fuzz::require(p.normals.empty() || p.normals.size() == p.positions_m.size(), "normals of another count");
    for (const glm::vec3& n : p.normals)
      fuzz::require(std::abs(glm::length(n) - 1.0f) < 1e-3f, "a normal that is not of unit length");
    fuzz::require(p.material < static_cast<int>(loaded.materials.size()), "a material index past the materials");
  }
  for (const model::Material& m : loaded.materials)
    for (const model::TextureSlot* slot : {&m.base_color, &m.metallic_roughness, &m.normal, &m.occlusion, &m.emissive})
      fuzz::require(slot->image < static_cast<int>(loaded.images.size()), "a texture past the images");
  for (const model::TextureImage& image : loaded.images)
    fuzz::require(image.rgba.size() == static_cast<std::size_t>(image.width) * image.height * 4,
                  "an image whose pixels are not width x height x 4");
  return 0;
}
