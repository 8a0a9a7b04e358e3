// glTF 2.0 files (.gltf with its .bin and images, .glb, embedded data URIs)
// into a MeshModel, with tinygltf (Debian's libtinygltf-dev) doing the
// parsing. A model is a file from a user, so everything tinygltf leaves
// unchecked is checked here, and a broken file costs one line naming the
// file and the field:
// - the JSON types (gltf_schema.hpp), which tinygltf skips silently;
// - every index (scene, node, mesh, accessor, buffer view, buffer,
//   material, texture, image) against what the file holds;
// - every accessor's bytes inside its buffer view and buffer;
// - vertex indices against the vertex count, attribute counts against each
//   other, positions, normals, UVs and transforms finite, normals not zero;
// - extensionsRequired that probelight does not implement (Draco, for one);
// - a node hierarchy with a cycle (cut, with a warning) or an instance count
//   that explodes (each instance is copied, so it counts in the size);
// - the size: files, decoded textures and vertices against ModelLimits.
// Images are decoded with OpenCV after the same header checks as camera
// frames (core/file_bytes.hpp), not by tinygltf's stb_image.
//
// The result is in the model frame: glTF's Y-up metres turned to the world's
// Z up (x, y, z) -> (x, -z, y), so a model's front (+Z in glTF) faces -Y.
#pragma once

#include <cstdint>
#include <string>

#include "model/mesh_model.hpp"

namespace probelight::model {

struct ModelLimits {
  // Each file read: the .gltf or .glb, and each buffer and image it names.
  std::uint64_t max_file_bytes = 256ull << 20;
  // What the loaded model holds (MeshModel::bytes): a Raspberry Pi 4 of
  // 2 GB runs probelight in about 250 MB, and the GL copy of a model doubles
  // it; 256 MiB (about 4 million triangles with UVs, or 64 textures of
  // 2048x2048) leaves the rest of the board's memory alone.
  std::uint64_t max_model_bytes = 256ull << 20;
};

// The model in `path`; false with `error` ("PATH: field: problem", one
// line) when the file cannot be used. Warnings (a cycle cut, optional
// extensions ignored, normals renormalised) go to the model's `warnings`.
bool loadGltfModel(const std::string& path, const ModelLimits& limits, MeshModel& model, std::string& error);

}  // namespace probelight::model
