// probelight.yaml (loadAppSettings): settings, or one ConfigError line naming
// the file.
#include "app/app_settings.hpp"
#include "config/config_reader.hpp"
#include "fuzz/fuzz_input.hpp"

using namespace probelight;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = fuzz::writeInput(data, size, "probelight.yaml");
  try {
    const AppSettings settings = loadAppSettings(path);
    fuzz::require(settings.save_every >= 0, "a negative output.save_every accepted");
  } catch (const config::ConfigError& error) {
    fuzz::requireOneLineNaming(error.what(), path);
  }
  return 0;
}
