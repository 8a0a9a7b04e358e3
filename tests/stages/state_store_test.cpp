// The state directory: atomic replacement survives a kill between the write
// and the rename; the lighting file round-trips and a damaged one is a clear
// error, not a crash.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "stages/state_store.hpp"

namespace probelight {
namespace {

namespace fs = std::filesystem;

class StateStore : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("probelight_state_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static std::string read(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  fs::path dir_;
};

TEST_F(StateStore, AKillBetweenWriteAndRenameLeavesTheOldFileWhole) {
  const fs::path path = dir_ / "lighting.json";
  std::string error;
  ASSERT_TRUE(writeFileAtomically(path, "old state\n", error)) << error;
  const std::string big_new(1 << 20, 'n');  // 1 MB: a torn write would show
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::string child_error;
    writeFileAtomically(path, big_new, child_error, [] { ::raise(SIGKILL); });
    _exit(0);  // not reached
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "the child must die mid-write";
  EXPECT_EQ(read(path), "old state\n");
  // The dead writer's temporary file may be left; the next write replaces the file all the same.
  ASSERT_TRUE(writeFileAtomically(path, big_new, error)) << error;
  EXPECT_EQ(read(path).size(), big_new.size());
}

TEST_F(StateStore, WriteFailureKeepsTheOldFileAndSaysWhy) {
  std::string error;
  EXPECT_FALSE(writeFileAtomically(dir_ / "no_such_dir" / "x.json", "data", error));
  EXPECT_NE(error.find("cannot create"), std::string::npos) << error;
}

// A lighting state as a fit leaves it: two dome lights, a clipped sun.
StoredLighting fittedLighting() {
  StoredLighting lighting;
  ibl::DomeLight light;
  light.direction_w = glm::normalize(glm::dvec3(0.3, -0.2, 0.9));
  light.rgb = {0.4, 0.5, 0.6};
  light.spread_rad = 0.12;
  lighting.lights = {light, light};
  lighting.dominant.found = true;
  lighting.dominant.direction_w = light.direction_w;
  lighting.dominant.rgb = light.rgb;
  lighting.placement = "clustered";
  ibl::ClippedLight sun;
  sun.direction_w = glm::normalize(glm::dvec3(0.5, 0.1, 0.8));
  sun.irradiance_rgb = {3.0, 2.9, 2.7};
  sun.texels = {100, 101, 4197};
  sun.texel_share = {0.5f, 0.25f, 0.25f};
  lighting.clipped_lights = {sun};
  lighting.clipped_share_at_fit = {0.75};
  lighting.exposure_at_fit = 2500.0;
  return lighting;
}

TEST_F(StateStore, LightingRoundTripsAndDamagedFilesAreClearErrors) {
  const StoredLighting lighting = fittedLighting();
  const ibl::DomeLight& light = lighting.lights[0];
  const ibl::ClippedLight& sun = lighting.clipped_lights[0];
  std::string error;
  ASSERT_TRUE(saveLighting(dir_ / "state", lighting, error)) << error;  // creates the directory
  const auto loaded = loadLighting(dir_ / "state", error);
  ASSERT_TRUE(loaded) << error;
  ASSERT_EQ(loaded->lights.size(), 2u);
  EXPECT_NEAR(glm::length(loaded->lights[0].direction_w - light.direction_w), 0.0, 1e-12);
  EXPECT_EQ(loaded->lights[1].rgb, light.rgb);
  EXPECT_EQ(loaded->placement, "clustered");
  EXPECT_TRUE(loaded->dominant.found);
  ASSERT_EQ(loaded->clipped_lights.size(), 1u);
  EXPECT_NEAR(glm::length(loaded->clipped_lights[0].direction_w - sun.direction_w), 0.0, 1e-12);
  EXPECT_EQ(loaded->clipped_lights[0].irradiance_rgb, sun.irradiance_rgb);
  EXPECT_EQ(loaded->clipped_lights[0].texels, sun.texels);
  EXPECT_EQ(loaded->clipped_lights[0].texel_share, sun.texel_share);
  EXPECT_EQ(loaded->clipped_share_at_fit, std::vector<double>{0.75});
  EXPECT_EQ(loaded->exposure_at_fit, 2500.0);

  // No file yet: nothing, and no error (the first boot).
  EXPECT_FALSE(loadLighting(dir_ / "empty", error));
  EXPECT_TRUE(error.empty()) << error;
  // Damaged: cut short, wrong format, a non-finite or non-unit value.
  const fs::path path = lightingStatePath(dir_ / "state");
  const std::string good = read(path);
  for (const std::string& bad : {good.substr(0, good.size() / 2), std::string("{\"format\": \"something else\"}"),
                                 std::string("{\"format\": \"probelight lighting 1\", \"lights\": [{\"direction\": [0, 0, 2], "
                                             "\"rgb\": [1, 1, 1], \"spread_rad\": 0.1}], \"dominant_light\": {\"found\": "
                                             "false, \"direction\": [0, 0, 1], \"rgb\": [0, 0, 0]}}"),
                                 // A clipped light with fewer shares than texels.
                                 std::string("{\"format\": \"probelight lighting 1\", \"lights\": [], \"dominant_light\": "
                                             "{\"found\": false, \"direction\": [0, 0, 1], \"rgb\": [0, 0, 0]}, "
                                             "\"clipped_lights\": [{\"direction\": [0, 0, 1], \"irradiance_rgb\": [1, 1, 1], "
                                             "\"texels\": [1, 2], \"texel_share\": [1], \"share_at_fit\": 1}]}")}) {
    std::ofstream(path) << bad;
    EXPECT_FALSE(loadLighting(dir_ / "state", error)) << bad;
    EXPECT_NE(error.find(path.string()), std::string::npos) << error;
  }
}

// Values a fit cannot produce, each in an otherwise good file (issue 15,
// D16): the file is refused whole with the field named, where they used to
// be loaded and shown (0 or 1,000 lights, rgb 1e308, a negative solid angle,
// exposure 1e-300, a zero dominant direction, texel -1 as 4294967295).
TEST_F(StateStore, ValuesNoFitCanProduceAreRefusedNamingTheField) {
  const StoredLighting lighting = fittedLighting();
  std::string error;
  ASSERT_TRUE(saveLighting(dir_ / "state", lighting, error)) << error;
  const fs::path path = lightingStatePath(dir_ / "state");
  const nlohmann::json good = nlohmann::json::parse(read(path));
  ASSERT_TRUE(loadLighting(dir_ / "state", error)) << error;

  const nlohmann::json thousand_lights = nlohmann::json(std::vector<nlohmann::json>(1000, good["lights"][0]));
  const std::vector<std::tuple<std::string, nlohmann::json, std::string>> cases = {
      {"/lights", nlohmann::json::array(), "field 'lights': 0 entries"},
      {"/lights", thousand_lights, "field 'lights': 1000 entries"},
      {"/lights/1/rgb/2", 1e308, "field 'lights[1].rgb[2]'"},
      {"/lights/0/solid_angle_sr", -0.5, "field 'lights[0].solid_angle_sr'"},
      {"/lights/0/spread_rad", "wide", "field 'lights[0].spread_rad': not a number"},
      {"/exposure_at_fit", 1e-300, "field 'exposure_at_fit'"},
      {"/dominant_light/direction", {0, 0, 0}, "field 'dominant_light.direction': not a unit direction"},
      {"/clipped_lights/0/texels/1", -1, "field 'clipped_lights[0].texels[1]'"},
      {"/clipped_lights/0/texel_share/0", 7.0, "field 'clipped_lights[0].texel_share[0]'"},
      {"/clipped_lights/0/texel_share", {0.5}, "field 'clipped_lights[0].texel_share': 1 entries"},
  };
  for (const auto& [pointer, value, says] : cases) {
    nlohmann::json bad = good;
    bad[nlohmann::json::json_pointer(pointer)] = value;
    std::ofstream(path) << bad.dump();
    EXPECT_FALSE(loadLighting(dir_ / "state", error)) << pointer;
    EXPECT_NE(error.find(path.string() + ": " + says), std::string::npos) << pointer << ": " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << "one line";
  }
  // A fit that found no dominant light stores a zero direction: that loads.
  nlohmann::json none = good;
  none["dominant_light"] = {{"found", false}, {"direction", {0, 0, 0}}, {"rgb", {0, 0, 0}}};
  std::ofstream(path) << none.dump();
  EXPECT_TRUE(loadLighting(dir_ / "state", error)) << error;
}

// A million nested brackets used to overflow the stack in nlohmann's
// parser (SIGSEGV): now a one-line refusal like any damaged file.
TEST_F(StateStore, DeeplyNestedJsonIsRefusedNotACrash) {
  std::string error;
  ASSERT_TRUE(saveLighting(dir_ / "state", fittedLighting(), error)) << error;
  const fs::path path = lightingStatePath(dir_ / "state");
  std::ofstream(path) << "{\"format\": \"probelight lighting 1\", \"lights\": " << std::string(1000000, '[')
                      << std::string(1000000, ']') << "}";
  EXPECT_FALSE(loadLighting(dir_ / "state", error));
  EXPECT_NE(error.find(path.string() + ": nested deeper than 16 levels"), std::string::npos) << error;
}

// The probe over views: saved and read back bit for bit; a missing file is
// no error; every way a file can be wrong is one line naming the file and
// the field, and nothing is returned.
TEST_F(StateStore, TheProbeRoundTripsAndEveryDamageIsNamed) {
  StoredProbe probe;
  probe.face_size = 4;
  probe.exposure_product = 8000.0 * 1.5;
  for (std::size_t i = 0; i < 6u * 4u * 4u; ++i)
    probe.texels.push_back({0.1f * i, 2.5f, 1e3f, i % 3 == 0 ? -7.0f : 1234.5f});
  std::string error;
  EXPECT_FALSE(loadProbe(dir_, error).has_value());
  EXPECT_EQ(error, "") << "no file yet is first boot, not an error";
  ASSERT_TRUE(saveProbe(dir_, probe, error)) << error;
  const std::optional<StoredProbe> back = loadProbe(dir_, error);
  ASSERT_TRUE(back.has_value()) << error;
  EXPECT_EQ(back->face_size, 4);
  EXPECT_EQ(back->exposure_product, probe.exposure_product);  // written with 17 digits
  ASSERT_EQ(back->texels.size(), probe.texels.size());
  for (std::size_t i = 0; i < probe.texels.size(); ++i) EXPECT_EQ(back->texels[i], probe.texels[i]) << i;

  // A probe that is not a cube is not written.
  StoredProbe torn = probe;
  torn.texels.pop_back();
  EXPECT_FALSE(saveProbe(dir_ / "other", torn, error));

  const std::string good = read(probeStatePath(dir_));
  const std::size_t header_end = good.find('\n') + 1;
  const std::string texels = good.substr(header_end);
  auto expectRefused = [&](const std::string& contents, const std::string& field) {
    std::ofstream(probeStatePath(dir_), std::ios::binary | std::ios::trunc) << contents;
    std::string why;
    EXPECT_FALSE(loadProbe(dir_, why).has_value()) << field;
    EXPECT_EQ(why.rfind(probeStatePath(dir_).string() + ": ", 0), 0u) << why;
    EXPECT_NE(why.find("field '" + field + "'"), std::string::npos) << why;
    EXPECT_EQ(why.find('\n'), std::string::npos) << why;
  };
  expectRefused("", "header");
  expectRefused(std::string(300, 'x'), "header");
  expectRefused("probelight lighting 1 4 12000\n" + texels, "header");
  expectRefused("probelight probe 1 0 12000\n" + texels, "face_size");
  expectRefused("probelight probe 1 2000 12000\n" + texels, "face_size");
  expectRefused("probelight probe 1 four 12000\n" + texels, "face_size");
  expectRefused("probelight probe 1 4 -5\n" + texels, "exposure");
  expectRefused("probelight probe 1 4 nan\n" + texels, "exposure");
  expectRefused("probelight probe 1 4 1e12\n" + texels, "exposure");
  expectRefused("probelight probe 1 4 12000 7\n" + texels, "header");
  expectRefused(good.substr(0, good.size() - 1), "texels");      // cut short
  expectRefused(good + std::string(16, '\0'), "texels");         // one texel too many
  expectRefused("probelight probe 1 3 12000\n" + texels, "texels");  // another face size's count
  auto withTexel = [&](std::size_t index, const glm::vec4& value) {
    std::string changed = good;
    std::memcpy(changed.data() + header_end + index * sizeof(glm::vec4), &value, sizeof value);
    return changed;
  };
  expectRefused(withTexel(5, {NAN, 0.0f, 0.0f, 1.0f}), "texels[5]");
  expectRefused(withTexel(6, {-1.0f, 0.0f, 0.0f, 1.0f}), "texels[6]");
  expectRefused(withTexel(7, {1.0f, INFINITY, 0.0f, 1.0f}), "texels[7]");
  expectRefused(withTexel(8, {1.0f, 1.0f, 1.0f, 2e9f}), "texels[8]");
  expectRefused(withTexel(9, {1.0f, 1.0f, 1.0f, NAN}), "texels[9]");
  // Unknown exposure (0) is a valid file: a source that cannot say.
  std::ofstream(probeStatePath(dir_), std::ios::binary | std::ios::trunc) << "probelight probe 1 4 0\n" << texels;
  const std::optional<StoredProbe> unknown = loadProbe(dir_, error);
  ASSERT_TRUE(unknown.has_value()) << error;
  EXPECT_EQ(unknown->exposure_product, 0.0);
}

}  // namespace
}  // namespace probelight
