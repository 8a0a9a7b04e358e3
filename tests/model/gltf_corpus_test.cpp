// The assimp project's glTF 2.0 test files (Debian's assimp-testmodels),
// read where Debian puts them: the valid ones load as the file describes
// them, the broken ones give one line naming the file and the field.
#include <gtest/gtest.h>

#include <filesystem>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>

#include <nlohmann/json.hpp>

#include "model/gltf_loader.hpp"

namespace probelight::model {
namespace {

const std::string kCorpus = "/usr/share/assimp/models/glTF2/";

MeshModel loadOk(const std::string& relative) {
  MeshModel model;
  std::string error;
  EXPECT_TRUE(loadGltfModel(kCorpus + relative, {}, model, error)) << error;
  return model;
}

std::string loadError(const std::string& relative) {
  MeshModel model;
  std::string error;
  EXPECT_FALSE(loadGltfModel(kCorpus + relative, {}, model, error)) << relative << " loaded";
  EXPECT_EQ(error.rfind(kCorpus + relative + ": ", 0), 0u) << "names the file: " << error;
  EXPECT_EQ(error.find('\n'), std::string::npos) << "one line: " << error;
  EXPECT_TRUE(model.primitives.empty()) << "nothing half-loaded is left";
  return error;
}

TEST(GltfCorpus, IsInstalled) {
  ASSERT_TRUE(std::filesystem::is_directory(kCorpus)) << "install Debian's assimp-testmodels (scripts/install-deps.sh)";
}

TEST(GltfCorpus, BrokenFilesNameTheField) {
  struct Case {
    const char* file;
    const char* names;
  };
  const Case cases[] = {
      {"IndexOutOfRange/IndexOutOfRange.gltf", ".indices"},
      {"IndexOutOfRange/AllIndicesOutOfRange.gltf", ".indices"},
      {"SchemaFailures/sceneWrongType.gltf", "scene: a string"},
      {"wrongTypes/badArray.gltf", "primitives"},
      {"wrongTypes/badExtension.gltf", "KHR_texture_transform: a string, not an object"},
      {"wrongTypes/badNumber.gltf", "normalTexture"},
      {"wrongTypes/badObject.gltf", "pbrMetallicRoughness: an array, not an object"},
      {"wrongTypes/badString.gltf", "name: the integer 42, not a string"},
      {"wrongTypes/badUint.gltf", "baseColorTexture.index: the integer -1"},
      {"BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb", "not finite"},
      {"BoxBadNormals-glTF-Binary/BoxBadNormals.glb", "NORMAL"},
      {"MissingBin/BoxTextured.gltf", "BoxTextured0.bin"},
      {"IncorrectVertexArrays/Cube.gltf", "35 vertices for TRIANGLES, not a multiple of 3"},
      {"TestNoRootNode/NoScene.gltf", "scene: scene 0, but the file has no scenes"},
      {"draco/2CylinderEngine.gltf", "KHR_draco_mesh_compression"},
  };
  for (const Case& c : cases) {
    const std::string error = loadError(c.file);
    EXPECT_NE(error.find(c.names), std::string::npos) << c.file << ": " << error;
    if (std::getenv("PROBELIGHT_PRINT_ERRORS")) std::cout << error << "\n";
  }
}

}  // namespace
}  // namespace probelight::model

namespace probelight::model {
namespace {

nlohmann::json glbJson(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  return nlohmann::json::parse(bytes.substr(20, length));
}

nlohmann::json gltfJson(const std::string& path) { return nlohmann::json::parse(std::ifstream(path)); }

// BoxTextured came from COLLADA (Z up) through COLLADA2GLTF, which put a
// Z-up-to-Y-up rotation on its root node. The loader's Y-up-to-Z-up turn
// undoes it, so the model's vertices are the file's POSITION floats as they
// are stored: read here from the .bin, by hand.
TEST(GltfCorpus, BoxTexturedInItsThreeFormsIsTheBoxOfItsBinaryFile) {
  std::ifstream bin(kCorpus + "BoxTextured-glTF/BoxTextured0.bin", std::ios::binary);
  std::vector<char> buffer((std::istreambuf_iterator<char>(bin)), std::istreambuf_iterator<char>());
  const nlohmann::json gltf = gltfJson(kCorpus + "BoxTextured-glTF/BoxTextured.gltf");
  const int position_accessor = gltf["meshes"][0]["primitives"][0]["attributes"]["POSITION"];
  const nlohmann::json& accessor = gltf["accessors"][position_accessor];
  const nlohmann::json& view = gltf["bufferViews"][accessor["bufferView"].get<int>()];
  const std::size_t count = accessor["count"], first = view.value("byteOffset", 0) + accessor.value("byteOffset", 0);
  const std::size_t stride = view.value("byteStride", 12);
  std::vector<glm::vec3> stored(count);
  for (std::size_t i = 0; i < count; ++i) std::memcpy(&stored[i], buffer.data() + first + i * stride, 12);

  std::vector<MeshModel> forms;
  std::vector<nlohmann::json> samplers;  // the forms differ in theirs
  for (const char* file : {"BoxTextured-glTF/BoxTextured.gltf", "BoxTextured-glTF-Binary/BoxTextured.glb",
                           "BoxTextured-glTF-Embedded/BoxTextured.gltf"}) {
    forms.push_back(loadOk(file));
    const std::string path = kCorpus + file;
    samplers.push_back((path.back() == 'b' ? glbJson(path) : gltfJson(path))["samplers"][0]);
  }
  auto wrapOf = [](int gl_enum) {
    return gl_enum == 33648 ? TextureWrap::kMirroredRepeat
                            : gl_enum == 33071 ? TextureWrap::kClampToEdge : TextureWrap::kRepeat;
  };
  for (std::size_t form = 0; form < forms.size(); ++form) {
    const MeshModel& model = forms[form];
    ASSERT_EQ(model.primitives.size(), 1u);
    const Primitive& box = model.primitives[0];
    EXPECT_EQ(model.triangleCount(), 12u);
    ASSERT_EQ(box.positions_m.size(), count);
    for (std::size_t i = 0; i < count; ++i)
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(box.positions_m[i][c], stored[i][c], 1e-6f) << "vertex " << i;  // float, rotated by exact 0/1s
    EXPECT_EQ(box.uv0.size(), count);
    EXPECT_EQ(box.normals.size(), count);
    EXPECT_NEAR(model.min_m.z, -0.5f, 1e-6f);
    EXPECT_NEAR(model.max_m.z, 0.5f, 1e-6f);
    ASSERT_EQ(model.materials.size(), 1u);
    const Material& material = model.materials[0];
    EXPECT_EQ(material.metallic_factor, 0.0f);
    EXPECT_EQ(material.roughness_factor, 1.0f) << "the schema's default";
    ASSERT_TRUE(material.base_color.present());
    EXPECT_EQ(material.base_color.wrap_s, wrapOf(samplers[form].value("wrapS", 10497))) << form;
    EXPECT_EQ(material.base_color.wrap_t, wrapOf(samplers[form].value("wrapT", 10497))) << form;
    ASSERT_EQ(model.images.size(), 1u);
    EXPECT_EQ(model.images[0].width, 211);  // CesiumLogoFlat.png, a palette PNG
    EXPECT_EQ(model.images[0].height, 211);
    EXPECT_EQ(model.images[0].rgba.size(), 211u * 211u * 4u);
    EXPECT_GT(model.load_ms, 0.0);
  }
  EXPECT_EQ(forms[0].materials[0].base_color.wrap_s, TextureWrap::kMirroredRepeat) << "the .gltf's sampler: 33648";
  // The same bytes whether the image and buffer are files, GLB chunks or data URIs.
  EXPECT_EQ(forms[0].images[0].rgba, forms[1].images[0].rgba);
  EXPECT_EQ(forms[0].images[0].rgba, forms[2].images[0].rgba);
  EXPECT_EQ(forms[0].primitives[0].indices, forms[1].primitives[0].indices);
}

// The triangle count from the file's own JSON: every node the scene
// reaches, its mesh's primitives' index counts / 3.
TEST(GltfCorpus, TwoCylinderEngineHasEveryTriangleItsNodesPlace) {
  const std::string file = "2CylinderEngine-glTF-Binary/2CylinderEngine.glb";
  const nlohmann::json gltf = glbJson(kCorpus + file);
  std::size_t expected = 0;
  std::vector<int> pending = gltf["scenes"][gltf.value("scene", 0)]["nodes"].get<std::vector<int>>();
  while (!pending.empty()) {
    const nlohmann::json& node = gltf["nodes"][pending.back()];
    pending.pop_back();
    if (node.contains("mesh"))
      for (const auto& primitive : gltf["meshes"][node["mesh"].get<int>()]["primitives"])
        expected += gltf["accessors"][primitive["indices"].get<int>()]["count"].get<std::size_t>() / 3;
    for (const auto& child : node.value("children", nlohmann::json::array())) pending.push_back(child);
  }
  const MeshModel model = loadOk(file);
  EXPECT_GT(expected, 1000u);
  EXPECT_EQ(model.triangleCount(), expected);
  EXPECT_EQ(model.materials.size(), gltf["materials"].size());
  EXPECT_TRUE(std::isfinite(model.min_m.x) && std::isfinite(model.max_m.x));
  EXPECT_LT(model.min_m.z, model.max_m.z);
}

TEST(GltfCorpus, TextureTransformsAreReadAsTheFileGivesThem) {
  const std::string file = "textureTransform/TextureTransformTest.gltf";
  const nlohmann::json gltf = gltfJson(kCorpus + file);
  const MeshModel model = loadOk(file);
  ASSERT_EQ(model.materials.size(), gltf["materials"].size());
  int transformed = 0;
  for (std::size_t i = 0; i < model.materials.size(); ++i) {
    const nlohmann::json& slot = gltf["materials"][i]["pbrMetallicRoughness"]["baseColorTexture"];
    const TextureSlot& loaded = model.materials[i].base_color;
    EXPECT_EQ(loaded.image, gltf["textures"][slot["index"].get<int>()]["source"].get<int>());
    if (!slot.contains("extensions")) continue;
    const nlohmann::json& transform = slot["extensions"]["KHR_texture_transform"];
    ++transformed;
    const std::vector<double> offset = transform.value("offset", std::vector<double>{0.0, 0.0});
    const std::vector<double> scale = transform.value("scale", std::vector<double>{1.0, 1.0});
    EXPECT_FLOAT_EQ(loaded.uv_offset.x, offset[0]) << i;
    EXPECT_FLOAT_EQ(loaded.uv_offset.y, offset[1]) << i;
    EXPECT_FLOAT_EQ(loaded.uv_scale.x, scale[0]) << i;
    EXPECT_FLOAT_EQ(loaded.uv_scale.y, scale[1]) << i;
    EXPECT_FLOAT_EQ(loaded.uv_rotation_rad, transform.value("rotation", 0.0)) << i;
  }
  EXPECT_GE(transformed, 6);
  EXPECT_EQ(model.images.size(), gltf["images"].size());
}

TEST(GltfCorpus, BoxTexcoordsReadsBothUvSets) {
  const MeshModel model = loadOk("BoxTexcoords-glTF/boxTexcoords.gltf");
  ASSERT_EQ(model.materials.size(), 1u);
  EXPECT_TRUE(model.materials[0].double_sided);
  EXPECT_EQ(model.materials[0].base_color.texcoord, 0);
  EXPECT_EQ(model.materials[0].metallic_roughness.texcoord, 1);
  ASSERT_FALSE(model.primitives.empty());
  EXPECT_FALSE(model.primitives[0].uv0.empty());
  EXPECT_FALSE(model.primitives[0].uv1.empty());
}

// Node 0's child is node 1, whose child is node 0: glTF forbids the cycle,
// assimp's test expects it read without looping forever. It holds no mesh.
TEST(GltfCorpus, RecursiveNodesLoadWithTheCycleCut) {
  const MeshModel model = loadOk("RecursiveNodes/RecursiveNodes.gltf");
  EXPECT_TRUE(model.primitives.empty());
  bool said_cycle = false, said_empty = false;
  for (const std::string& warning : model.warnings) {
    said_cycle = said_cycle || warning.find("nodes[1].children[0]: node 0 is its own ancestor") != std::string::npos;
    said_empty = said_empty || warning.find("no triangles") != std::string::npos;
  }
  EXPECT_TRUE(said_cycle);
  EXPECT_TRUE(said_empty);
}

// The sample the package installs (board/models, scripts/make-sample-model.py):
// it loads without a warning, as the model the README shows: its triangles,
// two textures (base colour and metallic-roughness, 256 px), a glossy glaze
// and a bare foot, 12 cm across, standing on its foot (glTF's Y up, the
// loader's Z up: the lowest point at z = 0).
TEST(GltfCorpus, TheShippedSampleBowlLoadsClean) {
  const std::string path = std::string(PROBELIGHT_TEST_DATA_DIR) + "/../../board/models/ceramic-bowl.glb";
  MeshModel model;
  std::string error;
  ASSERT_TRUE(loadGltfModel(path, {}, model, error)) << error;
  EXPECT_TRUE(model.warnings.empty()) << model.warnings.front();
  EXPECT_EQ(model.triangleCount(), 6656u);
  ASSERT_EQ(model.images.size(), 2u);
  for (const TextureImage& image : model.images) {
    EXPECT_EQ(image.width, 256);
    EXPECT_EQ(image.rgba.size(), static_cast<std::size_t>(image.width) * image.height * 4);
  }
  ASSERT_EQ(model.materials.size(), 1u);
  EXPECT_GE(model.materials[0].base_color.image, 0);
  EXPECT_GE(model.materials[0].metallic_roughness.image, 0);
  EXPECT_NEAR(model.max_m.x - model.min_m.x, 0.12f, 0.005f);
  EXPECT_NEAR(model.min_m.z, 0.0f, 1e-4f);
}

}  // namespace
}  // namespace probelight::model
