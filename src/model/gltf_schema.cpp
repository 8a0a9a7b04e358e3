#include "model/gltf_schema.hpp"

#include <cmath>
#include <vector>

namespace probelight::model {
namespace {

using nlohmann::json;

enum class Kind {
  kIndex,     // an integer >= 0 (a glTF id, an offset, a texCoord)
  kPositive,  // an integer >= 1 (a count, a byte length)
  kInteger,   // an enum's integer (componentType, mode, filter, wrap)
  kNumber,
  kString,
  kBoolean,
  kObject,     // checked against `schema`
  kIndexMap,   // an object whose values are indices (attributes)
  kAnyObject,  // an object not looked into
};

struct Schema;

struct Field {
  const char* name;
  Kind kind;
  bool array = false;         // an array of `kind`
  std::size_t length = 0;     // an array's exact length; 0: any (at least one)
  bool required = false;
  const Schema* schema = nullptr;  // for kObject
};

struct Schema {
  std::vector<Field> fields;
};

std::string describe(const json& value) {
  if (value.is_object()) return "an object";
  if (value.is_array()) return "an array";
  if (value.is_string()) return "a string";
  if (value.is_boolean()) return "true or false";
  if (value.is_null()) return "null";
  if (value.is_number_integer() || value.is_number_unsigned()) return "the integer " + value.dump();
  return "the number " + value.dump();
}

bool isInteger(const json& value) {
  if (value.is_number_integer() || value.is_number_unsigned()) return true;
  // JSON Schema's integer takes 1.0 as well.
  return value.is_number_float() && std::isfinite(value.get<double>()) && std::floor(value.get<double>()) == value.get<double>();
}

double numberOf(const json& value) { return value.get<double>(); }

const char* expected(Kind kind) {
  switch (kind) {
    case Kind::kIndex: return "an integer of 0 or more";
    case Kind::kPositive: return "an integer of 1 or more";
    case Kind::kInteger: return "an integer";
    case Kind::kNumber: return "a number";
    case Kind::kString: return "a string";
    case Kind::kBoolean: return "true or false";
    case Kind::kObject:
    case Kind::kIndexMap:
    case Kind::kAnyObject: return "an object";
  }
  return "";
}

std::string checkObject(const json& value, const Schema& schema, const std::string& where);

// Why `value` is not of `kind`, or "".
std::string checkValue(const json& value, Kind kind, const Schema* schema, const std::string& where) {
  bool ok = false;
  switch (kind) {
    case Kind::kIndex: ok = isInteger(value) && numberOf(value) >= 0.0; break;
    case Kind::kPositive: ok = isInteger(value) && numberOf(value) >= 1.0; break;
    case Kind::kInteger: ok = isInteger(value); break;
    case Kind::kNumber: ok = value.is_number() && std::isfinite(numberOf(value)); break;
    case Kind::kString: ok = value.is_string(); break;
    case Kind::kBoolean: ok = value.is_boolean(); break;
    case Kind::kObject:
    case Kind::kIndexMap:
    case Kind::kAnyObject: ok = value.is_object(); break;
  }
  if (!ok) return where + ": " + describe(value) + ", not " + expected(kind);
  if (kind == Kind::kObject) return checkObject(value, *schema, where);
  if (kind == Kind::kIndexMap)
    for (const auto& [key, entry] : value.items())
      if (std::string problem = checkValue(entry, Kind::kIndex, nullptr, where + "." + key); !problem.empty())
        return problem;
  return "";
}

std::string member(const std::string& where, const char* name) { return where.empty() ? name : where + "." + name; }

std::string checkObject(const json& value, const Schema& schema, const std::string& where) {
  // Every glTF object may have these.
  if (const auto it = value.find("name"); it != value.end() && !it->is_string())
    return member(where, "name") + ": " + describe(*it) + ", not a string";
  if (const auto it = value.find("extensions"); it != value.end() && !it->is_object())
    return member(where, "extensions") + ": " + describe(*it) + ", not an object";
  for (const Field& field : schema.fields) {
    const std::string at = member(where, field.name);
    const auto it = value.find(field.name);
    if (it == value.end()) {
      if (field.required) return at + ": missing (required)";
      continue;
    }
    if (!field.array) {
      if (std::string problem = checkValue(*it, field.kind, field.schema, at); !problem.empty()) return problem;
      continue;
    }
    if (!it->is_array()) return at + ": " + describe(*it) + ", not an array";
    if (it->empty()) return at + ": an empty array (the schema asks for at least one entry)";
    if (field.length != 0 && it->size() != field.length)
      return at + ": " + std::to_string(it->size()) + " entries, not " + std::to_string(field.length);
    for (std::size_t i = 0; i < it->size(); ++i)
      if (std::string problem = checkValue((*it)[i], field.kind, field.schema, at + "[" + std::to_string(i) + "]");
          !problem.empty())
        return problem;
  }
  return "";
}

Field required(Field field) {
  field.required = true;
  return field;
}
Field arrayOf(const char* name, Kind kind, std::size_t length = 0, const Schema* schema = nullptr) {
  return Field{name, kind, true, length, false, schema};
}
Field object(const char* name, const Schema* schema) { return Field{name, Kind::kObject, false, 0, false, schema}; }
Field scalar(const char* name, Kind kind) { return Field{name, kind}; }

const Schema& rootSchema() {
  static const Schema asset{{required(scalar("version", Kind::kString)), scalar("minVersion", Kind::kString),
                             scalar("generator", Kind::kString), scalar("copyright", Kind::kString)}};
  static const Schema scene{{arrayOf("nodes", Kind::kIndex)}};
  static const Schema node{{arrayOf("children", Kind::kIndex), scalar("mesh", Kind::kIndex),
                            scalar("camera", Kind::kIndex), scalar("skin", Kind::kIndex),
                            arrayOf("matrix", Kind::kNumber, 16), arrayOf("translation", Kind::kNumber, 3),
                            arrayOf("rotation", Kind::kNumber, 4), arrayOf("scale", Kind::kNumber, 3),
                            arrayOf("weights", Kind::kNumber)}};
  static const Schema primitive{{required(scalar("attributes", Kind::kIndexMap)), scalar("indices", Kind::kIndex),
                                 scalar("material", Kind::kIndex), scalar("mode", Kind::kIndex),
                                 arrayOf("targets", Kind::kIndexMap)}};
  static const Schema mesh{{required(arrayOf("primitives", Kind::kObject, 0, &primitive)),
                            arrayOf("weights", Kind::kNumber)}};
  static const Schema sparse{{required(scalar("count", Kind::kPositive)), required(scalar("indices", Kind::kAnyObject)),
                              required(scalar("values", Kind::kAnyObject))}};
  static const Schema accessor{{scalar("bufferView", Kind::kIndex), scalar("byteOffset", Kind::kIndex),
                                required(scalar("componentType", Kind::kInteger)),
                                scalar("normalized", Kind::kBoolean), required(scalar("count", Kind::kPositive)),
                                required(scalar("type", Kind::kString)), arrayOf("max", Kind::kNumber),
                                arrayOf("min", Kind::kNumber), object("sparse", &sparse)}};
  static const Schema buffer_view{{required(scalar("buffer", Kind::kIndex)), scalar("byteOffset", Kind::kIndex),
                                   required(scalar("byteLength", Kind::kPositive)),
                                   scalar("byteStride", Kind::kPositive), scalar("target", Kind::kInteger)}};
  static const Schema buffer{{scalar("uri", Kind::kString), required(scalar("byteLength", Kind::kPositive))}};
  static const Schema texture_transform{{arrayOf("offset", Kind::kNumber, 2), scalar("rotation", Kind::kNumber),
                                         arrayOf("scale", Kind::kNumber, 2), scalar("texCoord", Kind::kIndex)}};
  static const Schema texture_extensions{{object("KHR_texture_transform", &texture_transform)}};
  static const Schema texture_info{
      {required(scalar("index", Kind::kIndex)), scalar("texCoord", Kind::kIndex), object("extensions", &texture_extensions)}};
  static const Schema normal_texture_info{{required(scalar("index", Kind::kIndex)), scalar("texCoord", Kind::kIndex),
                                           scalar("scale", Kind::kNumber), object("extensions", &texture_extensions)}};
  static const Schema occlusion_texture_info{{required(scalar("index", Kind::kIndex)), scalar("texCoord", Kind::kIndex),
                                              scalar("strength", Kind::kNumber),
                                              object("extensions", &texture_extensions)}};
  static const Schema pbr{{arrayOf("baseColorFactor", Kind::kNumber, 4), object("baseColorTexture", &texture_info),
                           scalar("metallicFactor", Kind::kNumber), scalar("roughnessFactor", Kind::kNumber),
                           object("metallicRoughnessTexture", &texture_info)}};
  static const Schema material{{object("pbrMetallicRoughness", &pbr), object("normalTexture", &normal_texture_info),
                                object("occlusionTexture", &occlusion_texture_info),
                                object("emissiveTexture", &texture_info), arrayOf("emissiveFactor", Kind::kNumber, 3),
                                scalar("alphaMode", Kind::kString), scalar("alphaCutoff", Kind::kNumber),
                                scalar("doubleSided", Kind::kBoolean)}};
  static const Schema texture{{scalar("sampler", Kind::kIndex), scalar("source", Kind::kIndex)}};
  static const Schema image{{scalar("uri", Kind::kString), scalar("mimeType", Kind::kString),
                             scalar("bufferView", Kind::kIndex)}};
  static const Schema sampler{{scalar("magFilter", Kind::kInteger), scalar("minFilter", Kind::kInteger),
                               scalar("wrapS", Kind::kInteger), scalar("wrapT", Kind::kInteger)}};
  static const Schema root{{required(object("asset", &asset)), scalar("scene", Kind::kIndex),
                            arrayOf("scenes", Kind::kObject, 0, &scene), arrayOf("nodes", Kind::kObject, 0, &node),
                            arrayOf("meshes", Kind::kObject, 0, &mesh),
                            arrayOf("accessors", Kind::kObject, 0, &accessor),
                            arrayOf("bufferViews", Kind::kObject, 0, &buffer_view),
                            arrayOf("buffers", Kind::kObject, 0, &buffer),
                            arrayOf("materials", Kind::kObject, 0, &material),
                            arrayOf("textures", Kind::kObject, 0, &texture),
                            arrayOf("images", Kind::kObject, 0, &image),
                            arrayOf("samplers", Kind::kObject, 0, &sampler),
                            arrayOf("extensionsUsed", Kind::kString), arrayOf("extensionsRequired", Kind::kString),
                            arrayOf("cameras", Kind::kAnyObject), arrayOf("skins", Kind::kAnyObject),
                            arrayOf("animations", Kind::kAnyObject)}};
  return root;
}

}  // namespace

std::string checkGltfSchema(const json& root) {
  if (!root.is_object()) return "the file: " + describe(root) + ", not a glTF object";
  return checkObject(root, rootSchema(), "");
}

}  // namespace probelight::model
