#include "model/gltf_loader.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <new>
#include <set>
#include <sstream>
#include <utility>

#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <tiny_gltf.h>

#include "core/file_bytes.hpp"
#include "model/gltf_schema.hpp"

namespace probelight::model {
namespace {

namespace fs = std::filesystem;

// The required extensions probelight implements.
const std::set<std::string>& implementedExtensions() {
  static const std::set<std::string> kImplemented = {"KHR_texture_transform"};
  return kImplemented;
}

std::string mib(std::uint64_t bytes) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(1);
  out << static_cast<double>(bytes) / (1 << 20) << " MiB";
  return out.str();
}

std::string firstLine(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
  return line;
}

// ---- files and images, for tinygltf's callbacks ----

struct LoadContext {
  ModelLimits limits;
  std::uint64_t image_bytes = 0;  // decoded so far
};

bool fileExists(const std::string& path, void*) {
  std::error_code ignored;
  return fs::exists(path, ignored);
}

std::string keepPath(const std::string& path, void*) { return path; }  // no ~ or $VAR expansion

bool readFileForTinyGltf(std::vector<unsigned char>* bytes, std::string* error, const std::string& path, void* user) {
  const auto& context = *static_cast<const LoadContext*>(user);
  std::string why;
  if (readWholeFile(path, context.limits.max_file_bytes, *bytes, why)) return true;
  if (error) *error += path + ": " + why + "\n";
  return false;
}

bool writeNothing(std::string*, const std::string&, const std::vector<unsigned char>&, void*) { return false; }

// tinygltf 2.9 (Debian 13) asks a file's size before reading it, through a
// callback 2.8 (Debian 12) does not have (hence maybe_unused there), and
// calls it unchecked. Only a regular file gets a size, so a FIFO or a
// device is refused before it is opened; readFileForTinyGltf still checks
// the bytes it reads.
[[maybe_unused]] bool fileSizeForTinyGltf(std::size_t* size_bytes, std::string* error, const std::string& path, void*) {
  std::error_code failed;
  const auto status = fs::status(path, failed);
  const auto size = !failed && fs::is_regular_file(status) ? fs::file_size(path, failed) : std::uintmax_t{0};
  if (failed || !fs::is_regular_file(status)) {
    if (error) *error += path + ": not a regular file that can be read\n";
    return false;
  }
  *size_bytes = static_cast<std::size_t>(size);
  return true;
}

// The callbacks written field by field: 2.9 added a field between
// WriteWholeFile and user_data, so a braced list would put the user data
// into it. A template, so that the member's absence in 2.8 discards the
// statement instead of failing to compile.
template <typename Callbacks>
Callbacks fileCallbacks(LoadContext& context) {
  Callbacks callbacks{};
  callbacks.FileExists = fileExists;
  callbacks.ExpandFilePath = keepPath;
  callbacks.ReadWholeFile = readFileForTinyGltf;
  callbacks.WriteWholeFile = writeNothing;
  if constexpr (requires { callbacks.GetFileSizeInBytes; }) callbacks.GetFileSizeInBytes = fileSizeForTinyGltf;
  callbacks.user_data = &context;
  return callbacks;
}

// Decodes one texture image to RGBA8 with OpenCV, after the header checks
// camera frames get; counts it against the model's size.
bool decodeTextureImage(tinygltf::Image* image, const int index, std::string* error, std::string*, int, int,
                        const unsigned char* data, int size, void* user) {
  auto& context = *static_cast<LoadContext*>(user);
  const std::string which = "images[" + std::to_string(index) + "]";
  auto fail = [&](const std::string& why) {
    if (error) *error += which + ": " + why + "\n";
    return false;
  };
  if (data == nullptr || size <= 0) return fail("no image data");
  const std::vector<std::uint8_t> bytes(data, data + size);
  if (std::string problem = checkImageBytes(bytes); !problem.empty()) return fail(problem);
  cv::Mat decoded;
  try {
    decoded = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
    decoded = cv::Mat();
  } catch (const std::bad_alloc&) {
    return fail("does not fit in memory");
  }
  if (decoded.empty()) return fail("not an image OpenCV can decode");
  const std::uint64_t rgba_bytes = static_cast<std::uint64_t>(decoded.cols) * decoded.rows * 4;
  if (context.image_bytes + rgba_bytes > context.limits.max_model_bytes)
    return fail("its " + std::to_string(decoded.cols) + "x" + std::to_string(decoded.rows) +
                " pixels bring the model's textures to " + mib(context.image_bytes + rgba_bytes) + ", above the " +
                mib(context.limits.max_model_bytes) + " a model may hold");
  if (decoded.depth() == CV_16U) decoded.convertTo(decoded, CV_8U, 1.0 / 257.0);
  if (decoded.depth() != CV_8U) return fail("not 8 or 16 bits a channel");
  cv::Mat rgba;
  switch (decoded.channels()) {
    case 1: cv::cvtColor(decoded, rgba, cv::COLOR_GRAY2RGBA); break;
    case 3: cv::cvtColor(decoded, rgba, cv::COLOR_BGR2RGBA); break;
    case 4: cv::cvtColor(decoded, rgba, cv::COLOR_BGRA2RGBA); break;
    default: return fail(std::to_string(decoded.channels()) + " channels");
  }
  context.image_bytes += rgba_bytes;
  image->width = rgba.cols;
  image->height = rgba.rows;
  image->component = 4;
  image->bits = 8;
  image->pixel_type = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
  image->image.assign(rgba.data, rgba.data + rgba_bytes);
  return true;
}

// ---- accessors ----

int componentCount(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
  }
}

int componentBytes(int component_type) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

const char* typeName(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    default: return "a matrix";
  }
}

const char* componentName(int component_type) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: return "BYTE";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return "UNSIGNED_BYTE";
    case TINYGLTF_COMPONENT_TYPE_SHORT: return "SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return "UNSIGNED_SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return "UNSIGNED_INT";
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return "FLOAT";
    default: return "an unknown component type";
  }
}

// An accessor's elements, checked to lie inside its buffer.
struct AccessorData {
  const std::uint8_t* bytes = nullptr;
  std::size_t count = 0, stride = 0;
  int component_type = 0, components = 0;
  bool normalized = false;

  double component(std::size_t element, int c) const {
    const std::uint8_t* at = bytes + element * stride + static_cast<std::size_t>(c) * componentBytes(component_type);
    switch (component_type) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float value;
        std::memcpy(&value, at, sizeof value);
        return value;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? at[0] / 255.0 : at[0];
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        const auto value = static_cast<std::int8_t>(at[0]);
        return normalized ? std::max(value / 127.0, -1.0) : value;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        std::uint16_t value;
        std::memcpy(&value, at, sizeof value);
        return normalized ? value / 65535.0 : value;
      }
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        std::int16_t value;
        std::memcpy(&value, at, sizeof value);
        return normalized ? std::max(value / 32767.0, -1.0) : value;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        std::uint32_t value;
        std::memcpy(&value, at, sizeof value);
        return value;
      }
      default: return 0.0;
    }
  }
};

class Converter {
 public:
  Converter(const tinygltf::Model& gltf, const ModelLimits& limits, std::string tinygltf_warning, MeshModel& out)
      : gltf_(gltf), limits_(limits), tinygltf_warning_(std::move(tinygltf_warning)), out_(out) {}

  // "" or "field: problem".
  std::string run();

 private:
  std::string accessor(int index, const std::string& field, std::initializer_list<int> types,
                       std::initializer_list<int> component_types, AccessorData& data);
  std::string attributeFloats(const std::map<std::string, int>& attributes, const char* name,
                              const std::string& where, std::initializer_list<int> types,
                              std::initializer_list<int> component_types, bool allow_normalized, AccessorData& data,
                              bool& present);
  std::string materials();
  std::string textureSlot(int texture, int texcoord, const tinygltf::ExtensionMap& extensions, const std::string& where,
                          TextureSlot& slot);
  std::string nodes();
  std::string instance(int mesh, const glm::dmat4& to_model, const std::string& node_field);
  std::string primitive(const tinygltf::Primitive& source, const std::string& where, const glm::dmat4& to_model);
  std::string charge(std::uint64_t bytes, const std::string& where);
  void warnOnce(const std::string& key, const std::string& line) {
    if (warned_.insert(key).second) out_.warnings.push_back(line);
  }

  const tinygltf::Model& gltf_;
  ModelLimits limits_;
  std::string tinygltf_warning_;
  MeshModel& out_;
  std::uint64_t bytes_ = 0;
  std::set<std::string> warned_;
};

std::string Converter::charge(std::uint64_t bytes, const std::string& where) {
  bytes_ += bytes;
  if (bytes_ <= limits_.max_model_bytes) return "";
  return where + ": the model grows past " + mib(limits_.max_model_bytes) + " (" + std::to_string(out_.triangleCount()) +
         " triangles so far, textures included), more than a board can spare for it";
}

std::string Converter::accessor(int index, const std::string& field, std::initializer_list<int> types,
                                std::initializer_list<int> component_types, AccessorData& data) {
  const std::string where = field + " (accessors[" + std::to_string(index) + "])";
  if (index < 0 || static_cast<std::size_t>(index) >= gltf_.accessors.size())
    return field + ": accessor " + std::to_string(index) + ", but the file has " +
           std::to_string(gltf_.accessors.size());
  const tinygltf::Accessor& a = gltf_.accessors[static_cast<std::size_t>(index)];
  if (std::find(types.begin(), types.end(), a.type) == types.end())
    return where + ": of type " + typeName(a.type) + ", which this attribute cannot be";
  if (std::find(component_types.begin(), component_types.end(), a.componentType) == component_types.end())
    return where + ": of " + componentName(a.componentType) + " components, which this attribute cannot have";
  if (a.sparse.isSparse) return where + ": a sparse accessor, which probelight does not read";
  if (a.bufferView < 0) return where + ": no bufferView (all zeros), which probelight does not read";
  if (static_cast<std::size_t>(a.bufferView) >= gltf_.bufferViews.size())
    return where + ": bufferView " + std::to_string(a.bufferView) + ", but the file has " +
           std::to_string(gltf_.bufferViews.size());
  const tinygltf::BufferView& view = gltf_.bufferViews[static_cast<std::size_t>(a.bufferView)];
  if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= gltf_.buffers.size())
    return where + ": its bufferView's buffer " + std::to_string(view.buffer) + ", but the file has " +
           std::to_string(gltf_.buffers.size());
  const tinygltf::Buffer& buffer = gltf_.buffers[static_cast<std::size_t>(view.buffer)];
  // In this order, so that no product below can overflow: the view inside
  // its buffer (which is in memory, so at most a file's size), then every
  // count and offset inside the view.
  if (view.byteOffset > buffer.data.size() || view.byteLength > buffer.data.size() - view.byteOffset)
    return where + ": its bufferView (" + std::to_string(view.byteLength) + " bytes from byte " +
           std::to_string(view.byteOffset) + ") runs past its buffer's " + std::to_string(buffer.data.size()) + " bytes";
  const std::uint64_t element_bytes = static_cast<std::uint64_t>(componentCount(a.type)) * componentBytes(a.componentType);
  const std::uint64_t stride = view.byteStride != 0 ? view.byteStride : element_bytes;
  if (stride < element_bytes || stride > 252)
    return where + ": a byteStride of " + std::to_string(stride) + " for elements of " + std::to_string(element_bytes) +
           " bytes (the spec allows up to 252)";
  if (a.count == 0) return where + ": no elements";
  if (a.count > view.byteLength || a.byteOffset > view.byteLength ||
      static_cast<std::uint64_t>(a.byteOffset) + stride * (a.count - 1) + element_bytes > view.byteLength)
    return where + ": " + std::to_string(a.count) + " elements of " + std::to_string(element_bytes) + " bytes from byte " +
           std::to_string(a.byteOffset) + " do not fit in its bufferView's " + std::to_string(view.byteLength) + " bytes";
  data.bytes = buffer.data.data() + view.byteOffset + a.byteOffset;
  data.count = a.count;
  data.stride = static_cast<std::size_t>(stride);
  data.component_type = a.componentType;
  data.components = componentCount(a.type);
  data.normalized = a.normalized;
  return "";
}

std::string Converter::attributeFloats(const std::map<std::string, int>& attributes, const char* name,
                                       const std::string& where, std::initializer_list<int> types,
                                       std::initializer_list<int> component_types, bool allow_normalized,
                                       AccessorData& data, bool& present) {
  present = false;
  const auto it = attributes.find(name);
  if (it == attributes.end()) return "";
  const std::string field = where + ".attributes." + name;
  if (std::string problem = accessor(it->second, field, types, component_types, data); !problem.empty()) return problem;
  if (data.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT && !data.normalized && allow_normalized)
    return field + ": integer components that are not normalized";
  for (std::size_t i = 0; i < data.count; ++i)
    for (int c = 0; c < data.components; ++c)
      if (!std::isfinite(data.component(i, c)))
        return field + " (accessors[" + std::to_string(it->second) + "]): element " + std::to_string(i) +
               " is not finite";
  present = true;
  return "";
}

std::string Converter::textureSlot(int texture, int texcoord, const tinygltf::ExtensionMap& extensions,
                                   const std::string& where, TextureSlot& slot) {
  if (texture < 0) return "";
  if (static_cast<std::size_t>(texture) >= gltf_.textures.size())
    return where + ".index: texture " + std::to_string(texture) + ", but the file has " +
           std::to_string(gltf_.textures.size());
  const tinygltf::Texture& t = gltf_.textures[static_cast<std::size_t>(texture)];
  if (t.source < 0) {
    warnOnce(where, where + ": textures[" + std::to_string(texture) + "] has no image probelight reads; not used");
    return "";
  }
  if (static_cast<std::size_t>(t.source) >= gltf_.images.size())
    return "textures[" + std::to_string(texture) + "].source: image " + std::to_string(t.source) +
           ", but the file has " + std::to_string(gltf_.images.size());
  slot.image = t.source;
  slot.texcoord = texcoord;
  if (t.sampler >= 0) {
    if (static_cast<std::size_t>(t.sampler) >= gltf_.samplers.size())
      return "textures[" + std::to_string(texture) + "].sampler: sampler " + std::to_string(t.sampler) +
             ", but the file has " + std::to_string(gltf_.samplers.size());
    const tinygltf::Sampler& sampler = gltf_.samplers[static_cast<std::size_t>(t.sampler)];
    auto wrap = [&](int mode, const char* name, TextureWrap& into) -> std::string {
      switch (mode) {
        case TINYGLTF_TEXTURE_WRAP_REPEAT: into = TextureWrap::kRepeat; return "";
        case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE: into = TextureWrap::kClampToEdge; return "";
        case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT: into = TextureWrap::kMirroredRepeat; return "";
        default:
          return "samplers[" + std::to_string(t.sampler) + "]." + name + ": " + std::to_string(mode) +
                 " is not REPEAT (10497), CLAMP_TO_EDGE (33071) or MIRRORED_REPEAT (33648)";
      }
    };
    if (std::string problem = wrap(sampler.wrapS, "wrapS", slot.wrap_s); !problem.empty()) return problem;
    if (std::string problem = wrap(sampler.wrapT, "wrapT", slot.wrap_t); !problem.empty()) return problem;
    slot.nearest = sampler.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
  }
  if (const auto it = extensions.find("KHR_texture_transform"); it != extensions.end() && it->second.IsObject()) {
    const tinygltf::Value& transform = it->second;
    auto pair = [&](const char* key, glm::vec2& into) {
      if (!transform.Has(key)) return;
      const tinygltf::Value& value = transform.Get(key);
      if (value.IsArray() && value.ArrayLen() == 2)
        into = glm::vec2(value.Get(0).GetNumberAsDouble(), value.Get(1).GetNumberAsDouble());
    };
    pair("offset", slot.uv_offset);
    pair("scale", slot.uv_scale);
    if (transform.Has("rotation")) slot.uv_rotation_rad = static_cast<float>(transform.Get("rotation").GetNumberAsDouble());
    if (transform.Has("texCoord")) slot.texcoord = transform.Get("texCoord").GetNumberAsInt();
  }
  if (slot.texcoord > 1) {
    warnOnce(where + "tc", where + ": TEXCOORD_" + std::to_string(slot.texcoord) +
                               ", but probelight reads TEXCOORD_0 and _1; TEXCOORD_0 used");
    slot.texcoord = 0;
  }
  return "";
}

std::string Converter::materials() {
  for (std::size_t i = 0; i < gltf_.materials.size(); ++i) {
    const tinygltf::Material& m = gltf_.materials[i];
    const std::string where = "materials[" + std::to_string(i) + "]";
    Material material;
    material.name = m.name;
    const tinygltf::PbrMetallicRoughness& pbr = m.pbrMetallicRoughness;
    // The schema's ranges: factors in [0, 1], emissive and cutoff >= 0.
    auto unit = [&](double value, const std::string& field) -> std::string {
      if (value >= 0.0 && value <= 1.0) return "";
      return field + ": " + std::to_string(value) + " is outside [0, 1]";
    };
    if (pbr.baseColorFactor.size() != 4) return where + ".pbrMetallicRoughness.baseColorFactor: not 4 numbers";
    for (int c = 0; c < 4; ++c) {
      if (std::string problem = unit(pbr.baseColorFactor[c], where + ".pbrMetallicRoughness.baseColorFactor"); !problem.empty())
        return problem;
      material.base_color_factor[c] = static_cast<float>(pbr.baseColorFactor[c]);
    }
    if (std::string problem = unit(pbr.metallicFactor, where + ".pbrMetallicRoughness.metallicFactor"); !problem.empty())
      return problem;
    if (std::string problem = unit(pbr.roughnessFactor, where + ".pbrMetallicRoughness.roughnessFactor"); !problem.empty())
      return problem;
    material.metallic_factor = static_cast<float>(pbr.metallicFactor);
    material.roughness_factor = static_cast<float>(pbr.roughnessFactor);
    if (m.emissiveFactor.size() != 3) return where + ".emissiveFactor: not 3 numbers";
    for (int c = 0; c < 3; ++c) {
      if (!(m.emissiveFactor[c] >= 0.0) || !std::isfinite(m.emissiveFactor[c]))
        return where + ".emissiveFactor: " + std::to_string(m.emissiveFactor[c]) + " is below 0";
      material.emissive_factor[c] = static_cast<float>(m.emissiveFactor[c]);
    }
    if (!(m.alphaCutoff >= 0.0)) return where + ".alphaCutoff: " + std::to_string(m.alphaCutoff) + " is below 0";
    material.alpha_cutoff = static_cast<float>(m.alphaCutoff);
    if (m.alphaMode == "OPAQUE" || m.alphaMode.empty())
      material.alpha_mode = AlphaMode::kOpaque;
    else if (m.alphaMode == "MASK")
      material.alpha_mode = AlphaMode::kMask;
    else if (m.alphaMode == "BLEND")
      material.alpha_mode = AlphaMode::kBlend;
    else
      return where + ".alphaMode: \"" + m.alphaMode + "\" is not OPAQUE, MASK or BLEND";
    material.double_sided = m.doubleSided;
    material.normal_scale = static_cast<float>(m.normalTexture.scale);
    if (!(m.occlusionTexture.strength >= 0.0 && m.occlusionTexture.strength <= 1.0))
      return where + ".occlusionTexture.strength: " + std::to_string(m.occlusionTexture.strength) + " is outside [0, 1]";
    material.occlusion_strength = static_cast<float>(m.occlusionTexture.strength);
    const std::string p = where + ".pbrMetallicRoughness";
    for (std::string problem :
         {textureSlot(pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord, pbr.baseColorTexture.extensions,
                      p + ".baseColorTexture", material.base_color),
          textureSlot(pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord,
                      pbr.metallicRoughnessTexture.extensions, p + ".metallicRoughnessTexture",
                      material.metallic_roughness),
          textureSlot(m.normalTexture.index, m.normalTexture.texCoord, m.normalTexture.extensions,
                      where + ".normalTexture", material.normal),
          textureSlot(m.occlusionTexture.index, m.occlusionTexture.texCoord, m.occlusionTexture.extensions,
                      where + ".occlusionTexture", material.occlusion),
          textureSlot(m.emissiveTexture.index, m.emissiveTexture.texCoord, m.emissiveTexture.extensions,
                      where + ".emissiveTexture", material.emissive)})
      if (!problem.empty()) return problem;
    out_.materials.push_back(std::move(material));
  }
  return "";
}

// The node's transform: its matrix, or T * R * S.
std::string localTransform(const tinygltf::Node& node, const std::string& where, glm::dmat4& local) {
  local = glm::dmat4(1.0);
  if (!node.matrix.empty()) {
    if (node.matrix.size() != 16) return where + ".matrix: not 16 numbers";
    for (int i = 0; i < 16; ++i) glm::value_ptr(local)[i] = node.matrix[static_cast<std::size_t>(i)];  // column major
  } else {
    glm::dvec3 translation(0.0), scale(1.0);
    glm::dquat rotation(1.0, 0.0, 0.0, 0.0);
    if (node.translation.size() == 3) translation = {node.translation[0], node.translation[1], node.translation[2]};
    if (node.scale.size() == 3) scale = {node.scale[0], node.scale[1], node.scale[2]};
    if (node.rotation.size() == 4) {
      // glTF stores x, y, z, w.
      rotation = glm::dquat(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
      const double norm = glm::length(rotation);
      if (!(norm > 1e-12) || !std::isfinite(norm)) return where + ".rotation: not a rotation (a zero quaternion)";
      rotation /= norm;
    }
    local = glm::translate(glm::dmat4(1.0), translation) * glm::mat4_cast(rotation) * glm::scale(glm::dmat4(1.0), scale);
  }
  for (int i = 0; i < 16; ++i)
    if (!std::isfinite(glm::value_ptr(local)[i])) return where + ": its transform is not finite";
  return "";
}

std::string Converter::primitive(const tinygltf::Primitive& source, const std::string& where, const glm::dmat4& to_model) {
  if (source.mode >= 0 && source.mode <= 3) {
    warnOnce("mode" + std::to_string(source.mode),
             where + ".mode: points and lines (" + std::to_string(source.mode) + ") are not drawn");
    return "";
  }
  if (source.mode != TINYGLTF_MODE_TRIANGLES && source.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
      source.mode != TINYGLTF_MODE_TRIANGLE_FAN)
    return where + ".mode: " + std::to_string(source.mode) + " is not a glTF primitive mode";
  constexpr int kFloat = TINYGLTF_COMPONENT_TYPE_FLOAT, kUbyte = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                kUshort = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, kUint = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
  AccessorData positions, normals, tangents, uv0, uv1, colors;
  bool has_positions = false, has_normals = false, has_tangents = false, has_uv0 = false, has_uv1 = false,
       has_colors = false;
  const auto& attributes = source.attributes;
  for (std::string problem :
       {attributeFloats(attributes, "POSITION", where, {TINYGLTF_TYPE_VEC3}, {kFloat}, false, positions, has_positions),
        attributeFloats(attributes, "NORMAL", where, {TINYGLTF_TYPE_VEC3}, {kFloat}, false, normals, has_normals),
        attributeFloats(attributes, "TANGENT", where, {TINYGLTF_TYPE_VEC4}, {kFloat}, false, tangents, has_tangents),
        attributeFloats(attributes, "TEXCOORD_0", where, {TINYGLTF_TYPE_VEC2}, {kFloat, kUbyte, kUshort}, true, uv0,
                        has_uv0),
        attributeFloats(attributes, "TEXCOORD_1", where, {TINYGLTF_TYPE_VEC2}, {kFloat, kUbyte, kUshort}, true, uv1,
                        has_uv1),
        attributeFloats(attributes, "COLOR_0", where, {TINYGLTF_TYPE_VEC3, TINYGLTF_TYPE_VEC4},
                        {kFloat, kUbyte, kUshort}, true, colors, has_colors)})
    if (!problem.empty()) return problem;
  if (!has_positions) return where + ".attributes: no POSITION";
  const std::size_t vertices = positions.count;
  const std::pair<const char*, const AccessorData*> others[] = {
      {"NORMAL", has_normals ? &normals : nullptr},     {"TANGENT", has_tangents ? &tangents : nullptr},
      {"TEXCOORD_0", has_uv0 ? &uv0 : nullptr},         {"TEXCOORD_1", has_uv1 ? &uv1 : nullptr},
      {"COLOR_0", has_colors ? &colors : nullptr}};
  for (const auto& [name, data] : others)
    if (data && data->count != vertices)
      return where + ".attributes." + name + ": " + std::to_string(data->count) + " elements, but POSITION has " +
             std::to_string(vertices);

  // The indices, as triangles.
  std::vector<std::uint32_t> order;
  if (source.indices >= 0) {
    AccessorData indices;
    if (std::string problem = accessor(source.indices, where + ".indices", {TINYGLTF_TYPE_SCALAR}, {kUbyte, kUshort, kUint}, indices);
        !problem.empty())
      return problem;
    if (std::string problem = charge(indices.count * sizeof(std::uint32_t), where + ".indices"); !problem.empty())
      return problem;
    order.resize(indices.count);
    for (std::size_t i = 0; i < indices.count; ++i) {
      const double index = indices.component(i, 0);
      if (index >= static_cast<double>(vertices))
        return where + ".indices (accessors[" + std::to_string(source.indices) + "]): index " +
               std::to_string(static_cast<std::uint64_t>(index)) + " at " + std::to_string(i) + ", but POSITION has " +
               std::to_string(vertices) + " vertices";
      order[i] = static_cast<std::uint32_t>(index);
    }
  } else {
    order.resize(vertices);
    for (std::size_t i = 0; i < vertices; ++i) order[i] = static_cast<std::uint32_t>(i);
  }
  std::vector<std::uint32_t> triangles;
  if (source.mode == TINYGLTF_MODE_TRIANGLES) {
    // The spec's rule, and a sign of a truncated array.
    if (order.size() % 3 != 0)
      return where + (source.indices >= 0 ? ".indices: " : ".attributes.POSITION: ") + std::to_string(order.size()) +
             (source.indices >= 0 ? " indices" : " vertices") + " for TRIANGLES, not a multiple of 3";
    triangles = std::move(order);
  } else {
    if (order.size() < 3)
      return where + ": " + std::to_string(order.size()) + " vertices for a triangle strip or fan, fewer than 3";
    for (std::size_t i = 2; i < order.size(); ++i) {
      if (source.mode == TINYGLTF_MODE_TRIANGLE_FAN)
        triangles.insert(triangles.end(), {order[0], order[i - 1], order[i]});
      else if (i % 2 == 0)
        triangles.insert(triangles.end(), {order[i - 2], order[i - 1], order[i]});
      else  // every other strip triangle turns the other way
        triangles.insert(triangles.end(), {order[i - 1], order[i - 2], order[i]});
    }
  }

  Primitive out;
  out.material = source.material;
  if (source.material >= 0 && static_cast<std::size_t>(source.material) >= gltf_.materials.size())
    return where + ".material: material " + std::to_string(source.material) + ", but the file has " +
           std::to_string(gltf_.materials.size());
  const std::uint64_t vertex_bytes =
      vertices * (sizeof(glm::vec3) * (1 + has_normals) + sizeof(glm::vec4) * (has_tangents + has_colors) +
                  sizeof(glm::vec2) * (has_uv0 + has_uv1));
  if (std::string problem = charge(vertex_bytes, where); !problem.empty()) return problem;

  const glm::dmat3 linear(to_model);
  const glm::dmat3 normal_matrix = glm::inverseTranspose(linear);
  const double handedness = glm::determinant(linear) < 0.0 ? -1.0 : 1.0;
  out.positions_m.resize(vertices);
  for (std::size_t i = 0; i < vertices; ++i) {
    const glm::dvec4 p = to_model * glm::dvec4(positions.component(i, 0), positions.component(i, 1),
                                               positions.component(i, 2), 1.0);
    out.positions_m[i] = glm::vec3(p);
    if (!std::isfinite(out.positions_m[i].x) || !std::isfinite(out.positions_m[i].y) ||
        !std::isfinite(out.positions_m[i].z))
      return where + ".attributes.POSITION: vertex " + std::to_string(i) + " is not finite in float once placed";
  }
  if (has_normals) {
    out.normals.resize(vertices);
    for (std::size_t i = 0; i < vertices; ++i) {
      const glm::dvec3 n(normals.component(i, 0), normals.component(i, 1), normals.component(i, 2));
      const double length = glm::length(n);
      if (!(length > 1e-6))
        return where + ".attributes.NORMAL (accessors[" + std::to_string(attributes.at("NORMAL")) + "]): normal " +
               std::to_string(i) + " is zero";
      // The spec asks for unit normals; float storage keeps them within
      // 1e-6, and a few exporters' within 1e-3.
      if (std::abs(length - 1.0) > 1e-2)
        warnOnce(where + "normal", where + ".attributes.NORMAL: normal " + std::to_string(i) + " has length " +
                                       std::to_string(length) + ", not 1; normals renormalised");
      out.normals[i] = glm::vec3(glm::normalize(normal_matrix * (n / length)));
    }
  }
  if (has_tangents) {
    out.tangents.resize(vertices);
    for (std::size_t i = 0; i < vertices; ++i) {
      const glm::dvec3 t(tangents.component(i, 0), tangents.component(i, 1), tangents.component(i, 2));
      const double w = tangents.component(i, 3) < 0.0 ? -1.0 : 1.0;
      const glm::dvec3 placed = linear * t;
      const double length = glm::length(placed);
      out.tangents[i] = length > 1e-12 ? glm::vec4(glm::vec3(placed / length), w * handedness)
                                       : glm::vec4(0.0f, 0.0f, 0.0f, static_cast<float>(w * handedness));
    }
  }
  auto copy2 = [&](const AccessorData& data, std::vector<glm::vec2>& into) {
    into.resize(vertices);
    for (std::size_t i = 0; i < vertices; ++i)
      into[i] = glm::vec2(data.component(i, 0), data.component(i, 1));
  };
  if (has_uv0) copy2(uv0, out.uv0);
  if (has_uv1) copy2(uv1, out.uv1);
  if (has_colors) {
    out.colors.resize(vertices);
    for (std::size_t i = 0; i < vertices; ++i)
      out.colors[i] = glm::vec4(colors.component(i, 0), colors.component(i, 1), colors.component(i, 2),
                                colors.components == 4 ? colors.component(i, 3) : 1.0);
  }
  // A mirroring transform turns the triangles inside out: turn them back,
  // so front faces stay counter-clockwise.
  if (handedness < 0.0)
    for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) std::swap(triangles[t + 1], triangles[t + 2]);
  out.indices = std::move(triangles);
  if (!out.indices.empty()) out_.primitives.push_back(std::move(out));
  return "";
}

std::string Converter::instance(int mesh, const glm::dmat4& to_model, const std::string& node_field) {
  if (static_cast<std::size_t>(mesh) >= gltf_.meshes.size())
    return node_field + ".mesh: mesh " + std::to_string(mesh) + ", but the file has " + std::to_string(gltf_.meshes.size());
  // A scale of 0 hides a node (glTF's way to switch one off).
  if (std::abs(glm::determinant(glm::dmat3(to_model))) < 1e-30) return "";
  const tinygltf::Mesh& m = gltf_.meshes[static_cast<std::size_t>(mesh)];
  for (std::size_t p = 0; p < m.primitives.size(); ++p)
    if (std::string problem = primitive(m.primitives[p],
                                        "meshes[" + std::to_string(mesh) + "].primitives[" + std::to_string(p) + "]",
                                        to_model);
        !problem.empty())
      return problem;
  return "";
}

std::string Converter::nodes() {
  if (gltf_.scenes.empty()) {
    if (gltf_.defaultScene >= 0) return "scene: scene " + std::to_string(gltf_.defaultScene) + ", but the file has no scenes";
    return "scenes: none, so nothing to show";
  }
  if (gltf_.defaultScene >= static_cast<int>(gltf_.scenes.size()))
    return "scene: scene " + std::to_string(gltf_.defaultScene) + ", but the file has " +
           std::to_string(gltf_.scenes.size());
  const std::size_t scene_index = gltf_.defaultScene >= 0 ? static_cast<std::size_t>(gltf_.defaultScene) : 0;
  const tinygltf::Scene& scene = gltf_.scenes[scene_index];
  // glTF's Y up to the world's Z up: (x, y, z) -> (x, -z, y).
  glm::dmat4 z_up(1.0);
  z_up[1] = glm::dvec4(0.0, 0.0, 1.0, 0.0);
  z_up[2] = glm::dvec4(0.0, -1.0, 0.0, 0.0);
  // Depth first without recursion (a chain of 100,000 nodes must not
  // overflow the stack); a child already on the path is a cycle, cut.
  struct Visit {
    int node;
    glm::dmat4 world;
    std::size_t next_child;
  };
  std::vector<bool> on_path(gltf_.nodes.size(), false);
  constexpr std::size_t kMaxNodeInstances = 1000000;
  std::size_t visits = 0;
  for (std::size_t r = 0; r < scene.nodes.size(); ++r) {
    const int root = scene.nodes[r];
    const std::string root_field = "scenes[" + std::to_string(scene_index) + "].nodes[" + std::to_string(r) + "]";
    if (root < 0 || static_cast<std::size_t>(root) >= gltf_.nodes.size())
      return root_field + ": node " + std::to_string(root) + ", but the file has " + std::to_string(gltf_.nodes.size());
    std::vector<Visit> stack;
    auto enter = [&](int node, const glm::dmat4& parent) -> std::string {
      const std::string field = "nodes[" + std::to_string(node) + "]";
      // A node may have several parents (glTF forbids it, files do it), and
      // then each path is an instance: 30 levels of two parents each are a
      // billion. Instances with meshes count in the size; these bound the rest.
      if (++visits > kMaxNodeInstances)
        return field + ": the hierarchy reaches more than " + std::to_string(kMaxNodeInstances) +
               " node instances (nodes shared between parents)";
      glm::dmat4 local;
      if (std::string problem = localTransform(gltf_.nodes[static_cast<std::size_t>(node)], field, local); !problem.empty())
        return problem;
      const glm::dmat4 world = parent * local;
      const int mesh = gltf_.nodes[static_cast<std::size_t>(node)].mesh;
      if (mesh >= 0)
        if (std::string problem = instance(mesh, z_up * world, field); !problem.empty()) return problem;
      on_path[static_cast<std::size_t>(node)] = true;
      stack.push_back({node, world, 0});
      return "";
    };
    if (std::string problem = enter(root, glm::dmat4(1.0)); !problem.empty()) return problem;
    while (!stack.empty()) {
      Visit& top = stack.back();
      const tinygltf::Node& node = gltf_.nodes[static_cast<std::size_t>(top.node)];
      if (top.next_child >= node.children.size()) {
        on_path[static_cast<std::size_t>(top.node)] = false;
        stack.pop_back();
        continue;
      }
      const std::size_t c = top.next_child++;
      const int child = node.children[c];
      const std::string field = "nodes[" + std::to_string(top.node) + "].children[" + std::to_string(c) + "]";
      if (child < 0 || static_cast<std::size_t>(child) >= gltf_.nodes.size())
        return field + ": node " + std::to_string(child) + ", but the file has " + std::to_string(gltf_.nodes.size());
      if (on_path[static_cast<std::size_t>(child)]) {
        warnOnce(field, field + ": node " + std::to_string(child) +
                            " is its own ancestor (a cycle, which glTF does not allow); not followed");
        continue;
      }
      const glm::dmat4 parent = top.world;  // `top` may move when the stack grows
      if (std::string problem = enter(child, parent); !problem.empty()) return problem;
    }
  }
  return "";
}

// How deep the JSON's arrays and objects nest, from its text: tinygltf
// turns extras into its own values recursively, and 50,000 levels of
// brackets overflow the stack. glTF itself needs fewer than 10.
constexpr int kMaxJsonNesting = 64;
int jsonNesting(std::string_view text) {
  int depth = 0, deepest = 0;
  bool in_string = false, escaped = false;
  for (const char c : text) {
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
      if (deepest > kMaxJsonNesting) return deepest;  // enough to refuse
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

// Before tinygltf reads the file: it fails on a Draco file's accessors
// (they have no bufferView) with a message that hides the real reason.
std::string checkRequiredExtensions(const nlohmann::json& root) {
  const auto required = root.find("extensionsRequired");
  if (required == root.end()) return "";
  for (const auto& extension : *required)  // strings (checkGltfSchema)
    if (!implementedExtensions().count(extension.get<std::string>()))
      return "extensionsRequired: " + extension.get<std::string>() + " is not supported by probelight (it reads " +
             *implementedExtensions().begin() + ")";
  return "";
}

std::string Converter::run() {
  std::vector<std::string> ignored;
  for (const std::string& extension : gltf_.extensionsUsed)
    if (!implementedExtensions().count(extension)) ignored.push_back(extension);
  if (!ignored.empty()) {
    std::string line = "optional extensions ignored:";
    for (const std::string& extension : ignored) line += " " + extension;
    out_.warnings.push_back(line);
  }
  for (std::size_t i = 0; i < gltf_.images.size(); ++i) {
    const tinygltf::Image& image = gltf_.images[i];
    // tinygltf leaves an image it could not find (a missing file, a uri it
    // does not take for a data URI) empty, with only a warning.
    if (image.image.empty() || image.width <= 0 || image.height <= 0) {
      std::string uri = image.uri.substr(0, 48);
      if (uri.size() < image.uri.size()) uri += "...";
      return "images[" + std::to_string(i) + "]" + (uri.empty() ? "" : " (\"" + uri + "\")") + ": could not be read" +
             (tinygltf_warning_.empty() ? "" : " (" + firstLine(tinygltf_warning_) + ")");
    }
    if (std::string problem = charge(image.image.size(), "images"); !problem.empty()) return problem;
  }
  if (std::string problem = materials(); !problem.empty()) return problem;
  if (std::string problem = nodes(); !problem.empty()) return problem;
  for (std::size_t i = 0; i < gltf_.images.size(); ++i) {
    const tinygltf::Image& source = gltf_.images[i];
    TextureImage image;
    image.name = source.uri.empty() || source.uri.rfind("data:", 0) == 0 ? "images[" + std::to_string(i) + "]" : source.uri;
    image.width = source.width;
    image.height = source.height;
    image.rgba = source.image;
    out_.images.push_back(std::move(image));
  }
  bool any = false;
  for (const Primitive& p : out_.primitives)
    for (const glm::vec3& v : p.positions_m) {
      out_.min_m = any ? glm::min(out_.min_m, v) : v;
      out_.max_m = any ? glm::max(out_.max_m, v) : v;
      any = true;
    }
  if (out_.primitives.empty()) out_.warnings.push_back("the scene has no triangles to draw");
  return "";
}

}  // namespace

bool loadGltfModel(const std::string& path, const ModelLimits& limits, MeshModel& model, std::string& error) {
  const auto start = std::chrono::steady_clock::now();
  model = MeshModel{};
  model.source = path;
  auto fail = [&](const std::string& why) {
    error = path + ": " + why;
    model = MeshModel{};
    return false;
  };
  std::vector<std::uint8_t> bytes;
  std::string why;
  if (!readWholeFile(path, limits.max_file_bytes, bytes, why)) return fail(why);
  if (bytes.size() > std::numeric_limits<unsigned int>::max()) return fail("too large");
  // The JSON, from a .gltf or from a .glb's first chunk, for the type check.
  const bool binary = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
  std::string_view json_text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  if (binary) {
    auto le32 = [&](std::size_t at) {
      std::uint32_t value;
      std::memcpy(&value, bytes.data() + at, 4);
      return value;
    };
    if (bytes.size() < 20) return fail("a .glb cut short (no header)");
    if (le32(4) != 2) return fail("a .glb of version " + std::to_string(le32(4)) + ", not 2");
    const std::uint64_t json_bytes = le32(12);
    if (le32(16) != 0x4E4F534Au || 20 + json_bytes > bytes.size())
      return fail("a .glb whose first chunk is not its JSON, or is cut short");
    json_text = json_text.substr(20, static_cast<std::size_t>(json_bytes));
  }
  if (jsonNesting(json_text) > kMaxJsonNesting)
    return fail("its JSON is nested more than " + std::to_string(kMaxJsonNesting) + " levels deep");
  const nlohmann::json root = nlohmann::json::parse(json_text, nullptr, false);
  if (root.is_discarded()) return fail("not valid JSON");
  if (std::string problem = checkGltfSchema(root); !problem.empty()) return fail(problem);
  if (std::string problem = checkRequiredExtensions(root); !problem.empty()) return fail(problem);

  LoadContext context{limits, 0};
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(decodeTextureImage, &context);
  loader.SetFsCallbacks(fileCallbacks<tinygltf::FsCallbacks>(context));
  tinygltf::Model gltf;
  std::string gltf_error, gltf_warning;
  const std::string base_dir = fs::path(path).parent_path().string();
  bool loaded = false;
  try {
    loaded = binary ? loader.LoadBinaryFromMemory(&gltf, &gltf_error, &gltf_warning, bytes.data(),
                                                  static_cast<unsigned int>(bytes.size()), base_dir)
                    : loader.LoadASCIIFromString(&gltf, &gltf_error, &gltf_warning,
                                                 reinterpret_cast<const char*>(bytes.data()),
                                                 static_cast<unsigned int>(bytes.size()), base_dir);
  } catch (const std::bad_alloc&) {
    return fail("does not fit in memory");
  } catch (const std::exception& exception) {
    return fail(firstLine(exception.what()));
  }
  if (!loaded) return fail(gltf_error.empty() ? "tinygltf could not read it" : firstLine(gltf_error));
  if (!gltf_warning.empty()) model.warnings.push_back(firstLine(gltf_warning));
  try {
    if (std::string problem = Converter(gltf, limits, gltf_warning, model).run(); !problem.empty()) return fail(problem);
  } catch (const std::bad_alloc&) {
    return fail("does not fit in memory");
  }
  model.source = path;
  model.load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return true;
}

}  // namespace probelight::model
