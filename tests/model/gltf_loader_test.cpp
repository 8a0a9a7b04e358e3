// Made-up glTF files for what the corpus does not hold: the axis turn, a
// mirroring node, strips, deep and exploding hierarchies, the size limit,
// hostile images and buffers.
#include <sys/stat.h>

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "model/gltf_loader.hpp"

namespace probelight::model {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string base64(const std::vector<std::uint8_t>& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t chunk = bytes[i] << 16 | (i + 1 < bytes.size() ? bytes[i + 1] << 8 : 0) |
                                (i + 2 < bytes.size() ? bytes[i + 2] : 0);
    out += kAlphabet[chunk >> 18 & 63];
    out += kAlphabet[chunk >> 12 & 63];
    out += i + 1 < bytes.size() ? kAlphabet[chunk >> 6 & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[chunk & 63] : '=';
  }
  return out;
}

template <typename T>
void append(std::vector<std::uint8_t>& bytes, const std::vector<T>& values) {
  const auto* raw = reinterpret_cast<const std::uint8_t*>(values.data());
  bytes.insert(bytes.end(), raw, raw + values.size() * sizeof(T));
}

// One mesh of `positions` (and `normals` where given) with 32-bit `indices`
// (none: non-indexed), drawn in `mode`, under the node list `nodes` (node 0
// the scene's root; the caller puts "mesh": 0 on the nodes that carry it).
json meshFile(const std::vector<float>& positions, const std::vector<std::uint32_t>& indices, json nodes,
              int mode = 4, const std::vector<float>& normals = {}) {
  std::vector<std::uint8_t> buffer;
  append(buffer, positions);
  const std::size_t normals_at = buffer.size();
  append(buffer, normals);
  const std::size_t indices_at = buffer.size();
  append(buffer, indices);
  const std::size_t vertices = positions.size() / 3;
  json file = {{"asset", {{"version", "2.0"}}},
               {"scene", 0},
               {"scenes", {{{"nodes", {0}}}}},
               {"nodes", nodes},
               {"buffers", {{{"byteLength", buffer.size()},
                             {"uri", "data:application/octet-stream;base64," + base64(buffer)}}}},
               {"bufferViews", {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", positions.size() * 4}}}},
               {"accessors", {{{"bufferView", 0}, {"componentType", 5126}, {"count", vertices}, {"type", "VEC3"}}}}};
  json primitive = {{"attributes", {{"POSITION", 0}}}, {"mode", mode}};
  if (!normals.empty()) {
    file["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", normals_at}, {"byteLength", normals.size() * 4}});
    file["accessors"].push_back({{"bufferView", file["bufferViews"].size() - 1},
                                 {"componentType", 5126},
                                 {"count", vertices},
                                 {"type", "VEC3"}});
    primitive["attributes"]["NORMAL"] = file["accessors"].size() - 1;
  }
  if (!indices.empty()) {
    file["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", indices_at}, {"byteLength", indices.size() * 4}});
    file["accessors"].push_back({{"bufferView", file["bufferViews"].size() - 1},
                                 {"componentType", 5125},
                                 {"count", indices.size()},
                                 {"type", "SCALAR"}});
    primitive["indices"] = file["accessors"].size() - 1;
  }
  file["meshes"] = {{{"primitives", {primitive}}}};
  return file;
}

class GltfLoader : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("probelight_gltf_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const json& file, const std::string& name = "model.gltf") {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << file.dump();
    return path;
  }
  bool load(const json& file, MeshModel& model, std::string& error, const ModelLimits& limits = {}) {
    return loadGltfModel(write(file), limits, model, error);
  }

  fs::path dir_;
};

// glTF's +Y (up) is the world's +Z, and its +Z (the asset's front) -Y.
TEST_F(GltfLoader, YUpBecomesZUp) {
  MeshModel model;
  std::string error;
  ASSERT_TRUE(load(meshFile({0, 1, 0, 0, 0, 1, 1, 0, 0}, {}, json::array({{{"mesh", 0}}})), model, error)) << error;
  ASSERT_EQ(model.primitives.size(), 1u);
  const auto& p = model.primitives[0].positions_m;
  EXPECT_EQ(p[0], glm::vec3(0, 0, 1));
  EXPECT_EQ(p[1], glm::vec3(0, -1, 0));
  EXPECT_EQ(p[2], glm::vec3(1, 0, 0));
  EXPECT_EQ(model.primitives[0].indices, (std::vector<std::uint32_t>{0, 1, 2})) << "non-indexed: 0, 1, 2";
  EXPECT_EQ(model.min_m, glm::vec3(0, -1, 0));
  EXPECT_EQ(model.max_m, glm::vec3(1, 0, 1));
}

// A node's translation, rotation and scale, composed with its parent's.
TEST_F(GltfLoader, NodeTransformsCompose) {
  // Parent: translate (1, 0, 0); child: a quarter turn about glTF's Y, then
  // scale 2. The vertex (1, 0, 0): scaled (2, 0, 0), turned to (0, 0, -2),
  // moved to (1, 0, -2); in the world frame (1, 2, 0).
  const double half = std::sqrt(0.5);
  json nodes = json::array({{{"translation", {1, 0, 0}}, {"children", {1}}},
                            {{"rotation", {0, half, 0, half}}, {"scale", {2, 2, 2}}, {"mesh", 0}}});
  MeshModel model;
  std::string error;
  ASSERT_TRUE(load(meshFile({1, 0, 0, 0, 1, 0, 0, 0, 1}, {}, nodes), model, error)) << error;
  const glm::vec3 moved = model.primitives.at(0).positions_m[0];
  EXPECT_NEAR(moved.x, 1.0f, 1e-6f);
  EXPECT_NEAR(moved.y, 2.0f, 1e-6f);
  EXPECT_NEAR(moved.z, 0.0f, 1e-6f);
}

// A mirroring node (scale -1 in x) turns the triangle inside out; the
// loader turns it back, so the winding's normal agrees with the shading
// normal again.
TEST_F(GltfLoader, AMirroringNodeKeepsFrontFacesCounterClockwise) {
  for (const double sx : {1.0, -1.0}) {
    json nodes = json::array({{{"scale", {sx, 1, 1}}, {"mesh", 0}}});
    MeshModel model;
    std::string error;
    ASSERT_TRUE(load(meshFile({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2}, nodes, 4, {0, 0, 1, 0, 0, 1, 0, 0, 1}), model,
                     error))
        << error;
    const Primitive& p = model.primitives.at(0);
    const glm::vec3 a = p.positions_m[p.indices[0]], b = p.positions_m[p.indices[1]], c = p.positions_m[p.indices[2]];
    const glm::vec3 winding = glm::cross(b - a, c - a);
    EXPECT_GT(glm::dot(winding, p.normals[0]), 0.5f) << "scale x " << sx;
    EXPECT_NEAR(glm::length(p.normals[0]), 1.0f, 1e-6f);
  }
}

// A strip's every other triangle is wound the other way round in the
// list; the loader's triangles all face the same way.
TEST_F(GltfLoader, StripsAndFansBecomeTrianglesFacingOneWay) {
  for (const int mode : {5, 6}) {
    MeshModel model;
    std::string error;
    // A quad in glTF's XY plane (facing +Z), as a strip and as a fan.
    const std::vector<float> strip = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    const std::vector<float> fan = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    ASSERT_TRUE(load(meshFile(mode == 5 ? strip : fan, {}, json::array({{{"mesh", 0}}}), mode), model, error)) << error;
    const Primitive& p = model.primitives.at(0);
    ASSERT_EQ(p.triangleCount(), 2u) << mode;
    for (std::size_t t = 0; t < 2; ++t) {
      const glm::vec3 a = p.positions_m[p.indices[3 * t]], b = p.positions_m[p.indices[3 * t + 1]],
                      c = p.positions_m[p.indices[3 * t + 2]];
      // glTF's +Z is the world's -Y.
      EXPECT_LT(glm::cross(b - a, c - a).y, 0.0f) << "mode " << mode << " triangle " << t;
    }
  }
}

// 100,000 nodes in a chain: no recursion to overflow the stack.
TEST_F(GltfLoader, AChainOfAHundredThousandNodesLoads) {
  json nodes = json::array();
  constexpr int kDepth = 100000;
  for (int i = 0; i + 1 < kDepth; ++i) nodes.push_back({{"children", {i + 1}}, {"translation", {0, 1e-5, 0}}});
  nodes.push_back({{"mesh", 0}});
  MeshModel model;
  std::string error;
  ASSERT_TRUE(load(meshFile({0, 0, 0, 1, 0, 0, 0, 1, 0}, {}, nodes), model, error)) << error;
  // 99,999 steps of 1e-5 up (glTF's y): the world's z, within float's
  // accumulated rounding (the matrices compose in double).
  EXPECT_NEAR(model.primitives.at(0).positions_m[0].z, 0.99999, 1e-6);
}

// Each node listing the next one twice: 2^40 paths to the last.
TEST_F(GltfLoader, SharedNodesThatExplodeAreRefused) {
  json nodes = json::array();
  for (int i = 0; i < 40; ++i) nodes.push_back({{"children", {i + 1, i + 1}}});
  nodes.push_back(json::object());
  MeshModel model;
  std::string error;
  EXPECT_FALSE(load(meshFile({0, 0, 0, 1, 0, 0, 0, 1, 0}, {}, nodes), model, error));
  EXPECT_NE(error.find("node instances"), std::string::npos) << error;
}

TEST_F(GltfLoader, AModelAboveTheSizeLimitIsRefusedWithItsSize) {
  ModelLimits limits;
  limits.max_model_bytes = 1 << 10;
  std::vector<float> positions(3 * 300, 0.0f);  // 100 triangles: 3.5 KiB of positions
  for (std::size_t i = 0; i < positions.size(); ++i) positions[i] = static_cast<float>(i % 7);
  MeshModel model;
  std::string error;
  EXPECT_FALSE(load(meshFile(positions, {}, json::array({{{"mesh", 0}}})), model, error, limits));
  EXPECT_NE(error.find("grows past 0.0 MiB"), std::string::npos) << error;
  EXPECT_NE(error.find("more than a board can spare"), std::string::npos) << error;
  EXPECT_TRUE(load(meshFile(positions, {}, json::array({{{"mesh", 0}}})), model, error)) << "within the default";
}

// A PNG header claiming 65535x65535 (a 16 GiB decode) in a data URI: refused
// from its header, as camera frames are, before anything is decoded.
TEST_F(GltfLoader, ATextureWhoseHeaderClaimsTooManyPixelsIsRefusedUnread) {
  std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R',
                                   0, 0, 0xff, 0xff, 0, 0, 0xff, 0xff, 8, 6, 0, 0, 0, 0, 0, 0, 0};
  const std::uint8_t iend[] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xae, 0x42, 0x60, 0x82};
  png.insert(png.end(), std::begin(iend), std::end(iend));
  json file = meshFile({0, 0, 0, 1, 0, 0, 0, 1, 0}, {}, json::array({{{"mesh", 0}}}));
  file["images"] = {{{"uri", "data:image/png;base64," + base64(png)}}};
  file["textures"] = {{{"source", 0}}};
  file["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
  file["meshes"][0]["primitives"][0]["material"] = 0;
  MeshModel model;
  std::string error;
  EXPECT_FALSE(load(file, model, error));
  EXPECT_NE(error.find("images[0]: its header says 65535x65535"), std::string::npos) << error;
}

// A buffer whose uri is a FIFO would block a plain read forever.
TEST_F(GltfLoader, ABufferThatIsAFifoIsRefusedWithoutHanging) {
  ASSERT_EQ(::mkfifo((dir_ / "pipe.bin").c_str(), 0600), 0);
  json file = meshFile({0, 0, 0, 1, 0, 0, 0, 1, 0}, {}, json::array({{{"mesh", 0}}}));
  file["buffers"][0]["uri"] = "pipe.bin";
  MeshModel model;
  std::string error;
  EXPECT_FALSE(load(file, model, error));
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
}

// Extras may hold anything; 50,000 levels of it must not overflow a
// recursive reader.
TEST_F(GltfLoader, DeeplyNestedExtrasAreRefusedWithoutACrash) {
  json file = meshFile({0, 0, 0, 1, 0, 0, 0, 1, 0}, {}, json::array({{{"mesh", 0}}}));
  std::string text = file.dump();
  text.insert(text.size() - 1, ",\"extras\":" + std::string(50000, '[') + std::string(50000, ']'));
  const std::string path = (dir_ / "deep.gltf").string();
  std::ofstream(path) << text;
  MeshModel model;
  std::string error;
  EXPECT_FALSE(loadGltfModel(path, {}, model, error));
  EXPECT_NE(error.find("nested"), std::string::npos) << error;
}

TEST_F(GltfLoader, TheLargestIndexTellsWhether16BitIndicesDo) {
  std::vector<float> positions(3 * 70000, 0.0f);
  for (std::size_t i = 0; i < positions.size(); ++i) positions[i] = static_cast<float>(i % 5);
  MeshModel model;
  std::string error;
  ASSERT_TRUE(load(meshFile(positions, {0, 1, 69999}, json::array({{{"mesh", 0}}})), model, error)) << error;
  EXPECT_EQ(model.maxIndex(), 69999u);
  EXPECT_EQ(model.triangleCount(), 1u);
  EXPECT_EQ(model.vertexCount(), 70000u);
}

}  // namespace
}  // namespace probelight::model

namespace probelight::model {
namespace {

// tinygltf leaves an image it cannot find empty, with a warning only (found
// by fuzz/gltf_model_fuzzer.cpp: a "data:image/png;base28," uri, taken for a
// file name): the model is refused, naming the image, not shown untextured.
TEST_F(GltfLoader, AnImageThatCannotBeReadIsRefused) {
  for (const char* uri : {"missing.png", "data:image/png;base28,iVBORw0KGgo="}) {
    json file = meshFile({0, 0, 0, 1, 0, 0, 0, 1, 0}, {}, json::array({{{"mesh", 0}}}));
    file["images"] = {{{"uri", uri}}};
    file["textures"] = {{{"source", 0}}};
    file["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
    file["meshes"][0]["primitives"][0]["material"] = 0;
    MeshModel model;
    std::string error;
    EXPECT_FALSE(load(file, model, error)) << uri;
    EXPECT_NE(error.find("images[0] (\"" + std::string(uri).substr(0, 20)), std::string::npos) << error;
    EXPECT_NE(error.find("could not be read"), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace probelight::model

namespace probelight::model {
namespace {

// A count of 2^62 times a stride of 12 wraps a 64-bit size to a small one;
// the accessor is measured against its view before any product is formed.
TEST_F(GltfLoader, AnAccessorCountThatWouldWrapIsRefused) {
  json file = meshFile({0, 0, 0, 1, 0, 0, 0, 1, 0}, {}, json::array({{{"mesh", 0}}}));
  file["accessors"][0]["count"] = 4611686018427387904ull;
  MeshModel model;
  std::string error;
  EXPECT_FALSE(load(file, model, error));
  EXPECT_NE(error.find("accessors[0]"), std::string::npos) << error;
}

}  // namespace
}  // namespace probelight::model
