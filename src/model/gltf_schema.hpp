// The JSON types of a glTF 2.0 file, checked before tinygltf reads it.
// tinygltf 2.7 skips a property of the wrong type without a word ("scene":
// "hello" becomes no scene, "name": 42 no name, a "pbrMetallicRoughness"
// array a default material), so a broken file would load as another model.
// This walks the objects probelight reads, with the glTF 2.0 schema's types
// and required properties, and names the first field that breaks it.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace probelight::model {

// "" when `root` (a glTF file's JSON) has the schema's types where
// probelight reads it; otherwise the first field that does not, as
// "materials[0].pbrMetallicRoughness: an object, not an array". Unknown
// properties and extensions other than KHR_texture_transform are not
// checked (the schema allows them).
std::string checkGltfSchema(const nlohmann::json& root);

}  // namespace probelight::model
