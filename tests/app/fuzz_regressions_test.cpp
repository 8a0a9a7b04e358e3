// Inputs the fuzz targets (fuzz/) found that crashed a loader, kept in
// tests/data/fuzz-regressions/ and named after the target that found them:
// each must now give one ConfigError line naming the file.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <map>
#include <string>

#include "app/app_settings.hpp"
#include "config/camera_file.hpp"
#include "config/config_reader.hpp"
#include "config/rig_file.hpp"

namespace probelight {
namespace {

TEST(FuzzRegressions, EveryCrashFoundIsNowOneConfigErrorNamingTheFile) {
  const std::map<std::string, std::function<void(const std::string&)>> loaders = {
      {"camera_yaml", [](const std::string& path) { config::loadCameraFile(path); }},
      {"rig_yaml", [](const std::string& path) { config::loadRigFile(path); }},
      {"probelight_yaml", [](const std::string& path) { loadAppSettings(path); }},
  };
  int checked = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(PROBELIGHT_TEST_DATA_DIR) + "/fuzz-regressions")) {
    const std::string path = entry.path().string();
    const std::string name = entry.path().filename().string();
    const auto loader = loaders.find(name.substr(0, name.find('-')));
    ASSERT_NE(loader, loaders.end()) << name << ": name it <target>-<what>.yaml";
    try {
      loader->second(path);
      ADD_FAILURE() << name << ": loaded";
    } catch (const config::ConfigError& error) {
      const std::string message = error.what();
      EXPECT_EQ(message.rfind(path, 0), 0u) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
    ++checked;
  }
  EXPECT_GE(checked, 2);
}

}  // namespace
}  // namespace probelight
