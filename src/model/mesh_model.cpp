#include "model/mesh_model.hpp"

#include <algorithm>

namespace probelight::model {

std::size_t MeshModel::triangleCount() const {
  std::size_t count = 0;
  for (const Primitive& primitive : primitives) count += primitive.triangleCount();
  return count;
}

std::size_t MeshModel::vertexCount() const {
  std::size_t count = 0;
  for (const Primitive& primitive : primitives) count += primitive.positions_m.size();
  return count;
}

std::uint64_t MeshModel::bytes() const {
  std::uint64_t total = 0;
  for (const Primitive& p : primitives)
    total += p.positions_m.size() * sizeof(glm::vec3) + p.normals.size() * sizeof(glm::vec3) +
             p.tangents.size() * sizeof(glm::vec4) + (p.uv0.size() + p.uv1.size()) * sizeof(glm::vec2) +
             p.colors.size() * sizeof(glm::vec4) + p.indices.size() * sizeof(std::uint32_t);
  for (const TextureImage& image : images) total += image.rgba.size();
  return total;
}

std::uint32_t MeshModel::maxIndex() const {
  std::uint32_t largest = 0;
  for (const Primitive& p : primitives)
    if (!p.indices.empty()) largest = std::max(largest, *std::max_element(p.indices.begin(), p.indices.end()));
  return largest;
}

}  // namespace probelight::model
