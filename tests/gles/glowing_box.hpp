// A model whose pixels are one known colour: a 6 cm box lit by nothing
// (black maps) that glows a flat emissive colour, for the GPU tests of what
// the model renderer does to its pixels (edges, noise) rather than to its
// shading.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include <glm/glm.hpp>

#include "ibl/cube_map.hpp"
#include "model/mesh_model.hpp"
#include "passes/environment_maps.hpp"

namespace probelight::test {

// A 6 cm box on the tag, turned 27 degrees about the vertical: seen from
// above at an angle its outline is a hexagon, six edges at six angles.
inline model::MeshModel glowingBox(const glm::vec3& emissive) {
  model::MeshModel box;
  model::Primitive p;
  const float h = 0.03f;
  const glm::vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int axis = 0; axis < 3; ++axis)
    for (float side : {-1.0f, 1.0f}) {
      const glm::vec3 n = side * axes[axis], u = axes[(axis + 1) % 3], v = axes[(axis + 2) % 3];
      const auto base = static_cast<std::uint32_t>(p.positions_m.size());
      for (const auto& [a, b] : {std::pair{-1.0f, -1.0f}, {1.0f, -1.0f}, {1.0f, 1.0f}, {-1.0f, 1.0f}}) {
        p.positions_m.push_back(h * (n + a * u + b * v));
        p.normals.push_back(n);
      }
      p.indices.insert(p.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
  p.material = 0;
  box.primitives.push_back(p);
  model::Material glow;
  glow.name = "glow";
  glow.base_color_factor = {0.0f, 0.0f, 0.0f, 1.0f};
  glow.metallic_factor = 1.0f;  // F0 = base colour = 0: no specular either
  glow.emissive_factor = emissive;
  glow.double_sided = true;     // the winding then cannot matter: the outline is the test
  box.materials.push_back(glow);
  box.min_m = glm::vec3(-h);
  box.max_m = glm::vec3(h);
  return box;
}

inline glm::dmat4 glowingBoxPlacement() {
  const double turn = 27.0 * 3.14159265358979 / 180.0;
  glm::dmat4 world(1.0);
  world[0] = {std::cos(turn), std::sin(turn), 0.0, 0.0};
  world[1] = {-std::sin(turn), std::cos(turn), 0.0, 0.0};
  world[3] = {0.0, 0.0, 0.03, 1.0};
  return world;
}

// Black surroundings (reflection and diffuse maps): the box's colour is its
// emissive alone. False with the reason in `error`.
inline bool initBlackMaps(passes::EnvironmentMaps& maps, const gles::Capabilities& caps, std::string& error) {
  if (!maps.init(caps, {}, error)) return false;
  ibl::CubeMapRGB black(maps.settings().reflection_face_size);
  for (auto& face : black.faces) std::fill(face.begin(), face.end(), glm::vec3(0.0f));
  return maps.setReflection(black, error) && maps.updateDiffuse(error);
}

}  // namespace probelight::test
