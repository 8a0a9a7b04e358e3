// The KMS display's choice of screen and mode, against described hardware
// (libdrm's own structures, filled as a Raspberry Pi with two HDMI ports
// reports them), and its failure on a machine without a KMS device.
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <xf86drm.h>

#include "binary_test_support.hpp"
#include "display/kms_display.hpp"
#include "display/kms_modes.hpp"

namespace probelight {
namespace {

// A CEA mode as the kernel lists it: pixel clock (kHz) and totals.
drmModeModeInfo ceaMode(int width, int height, int clock_khz, int htotal, int vtotal, bool preferred) {
  drmModeModeInfo mode{};
  mode.hdisplay = static_cast<std::uint16_t>(width);
  mode.vdisplay = static_cast<std::uint16_t>(height);
  mode.clock = static_cast<std::uint32_t>(clock_khz);
  mode.htotal = static_cast<std::uint16_t>(htotal);
  mode.vtotal = static_cast<std::uint16_t>(vtotal);
  mode.vrefresh = static_cast<std::uint32_t>(clock_khz * 1000.0 / (htotal * vtotal) + 0.5);
  mode.type = DRM_MODE_TYPE_DRIVER | (preferred ? DRM_MODE_TYPE_PREFERRED : 0);
  std::snprintf(mode.name, sizeof mode.name, "%dx%d", width, height);
  return mode;
}

// HDMI-A-1 with nothing plugged in, HDMI-A-2 with a 1080p monitor that
// prefers 1920x1080@60 and also offers 50 Hz, 1280x720 and 640x480.
std::vector<ConnectorDescription> twoHdmiPorts(std::vector<drmModeModeInfo>& modes) {
  modes = {ceaMode(1920, 1080, 148500, 2200, 1125, true), ceaMode(1920, 1080, 148500, 2640, 1125, false),
           ceaMode(1280, 720, 74250, 1650, 750, false), ceaMode(640, 480, 25175, 800, 525, false)};
  drmModeConnector empty{};
  empty.connector_id = 32;
  empty.connector_type = DRM_MODE_CONNECTOR_HDMIA;
  empty.connector_type_id = 1;
  empty.connection = DRM_MODE_DISCONNECTED;
  drmModeConnector monitor{};
  monitor.connector_id = 42;
  monitor.connector_type = DRM_MODE_CONNECTOR_HDMIA;
  monitor.connector_type_id = 2;
  monitor.connection = DRM_MODE_CONNECTED;
  monitor.count_modes = static_cast<int>(modes.size());
  monitor.modes = modes.data();
  return {describeConnector(empty), describeConnector(monitor)};
}

TEST(KmsModes, DescribesLibdrmsConnectorsAndExactRefreshRates) {
  std::vector<drmModeModeInfo> modes;
  const std::vector<ConnectorDescription> ports = twoHdmiPorts(modes);
  ASSERT_EQ(ports.size(), 2u);
  EXPECT_EQ(ports[0].name, "HDMI-A-1");
  EXPECT_FALSE(ports[0].connected);
  EXPECT_EQ(ports[1].name, "HDMI-A-2");
  EXPECT_EQ(ports[1].id, 42u);
  ASSERT_EQ(ports[1].modes.size(), 4u);
  // 148.5 MHz / (2200 x 1125) = 60 Hz exactly; / (2640 x 1125) = 50 Hz;
  // 25.175 MHz / (800 x 525) = 59.94 Hz (VGA).
  EXPECT_NEAR(ports[1].modes[0].refresh_hz, 60.0, 1e-9);
  EXPECT_NEAR(ports[1].modes[1].refresh_hz, 50.0, 1e-9);
  EXPECT_NEAR(ports[1].modes[3].refresh_hz, 59.94, 0.01);
  EXPECT_TRUE(ports[1].modes[0].preferred);
  EXPECT_FALSE(ports[1].modes[2].preferred);
}

TEST(KmsModes, PicksTheConnectedScreenAndItsPreferredModeOrTheConfiguredOne) {
  std::vector<drmModeModeInfo> modes;
  const std::vector<ConnectorDescription> ports = twoHdmiPorts(modes);
  std::string error;
  // Default: the first connected connector (HDMI-A-2), its preferred mode.
  auto choice = chooseMode(ports, {}, error);
  ASSERT_TRUE(choice) << error;
  EXPECT_EQ(choice->connector_index, 1u);
  EXPECT_EQ(choice->mode_index, 0u);
  EXPECT_EQ(choice->summary, "HDMI-A-2 1920x1080@60.00");
  // A configured size: the highest refresh at it, or the one asked for.
  ModeRequest request;
  request.width_px = 1920;
  request.height_px = 1080;
  request.refresh_hz = 50.0;
  choice = chooseMode(ports, request, error);
  ASSERT_TRUE(choice) << error;
  EXPECT_EQ(choice->mode_index, 1u);
  request = {};
  request.width_px = 640;
  request.height_px = 480;
  choice = chooseMode(ports, request, error);
  ASSERT_TRUE(choice) << error;
  EXPECT_EQ(choice->mode_index, 3u);
}

TEST(KmsModes, SaysWhatThereIsWhenNothingFits) {
  std::vector<drmModeModeInfo> modes;
  const std::vector<ConnectorDescription> ports = twoHdmiPorts(modes);
  std::string error;
  ModeRequest request;
  request.width_px = 3840;
  request.height_px = 2160;
  EXPECT_FALSE(chooseMode(ports, request, error));
  EXPECT_NE(error.find("does not offer 3840x2160"), std::string::npos) << error;
  EXPECT_NE(error.find("1280x720@60.00"), std::string::npos) << error;
  request = {};
  request.connector = "HDMI-A-1";
  EXPECT_FALSE(chooseMode(ports, request, error));
  EXPECT_NE(error.find("HDMI-A-1 has no screen plugged in"), std::string::npos) << error;
  request.connector = "DSI-1";
  EXPECT_FALSE(chooseMode(ports, request, error));
  EXPECT_NE(error.find("no connector DSI-1"), std::string::npos) << error;
  EXPECT_NE(error.find("HDMI-A-1 (nothing plugged in), HDMI-A-2"), std::string::npos) << error;
  std::vector<ConnectorDescription> unplugged = {ports[0]};
  EXPECT_FALSE(chooseMode(unplugged, {}, error));
  EXPECT_NE(error.find("no screen is connected"), std::string::npos) << error;
  EXPECT_FALSE(chooseMode({}, {}, error));
}

// This machine has no /dev/dri: the display says so and points at headless,
// and `run --display kms` fails with that one line.
class KmsDisplayFailure : public testing::BinaryTest {
 protected:
  KmsDisplayFailure() : BinaryTest("kms") {}
};

TEST_F(KmsDisplayFailure, NoKmsDeviceIsOneLineSuggestingHeadless) {
  if (std::filesystem::exists("/dev/dri/card0")) GTEST_SKIP() << "this machine has a KMS device";
  KmsDisplay display({});
  std::string error;
  EXPECT_FALSE(display.open(640, 480, error));
  EXPECT_NE(error.find("no KMS device"), std::string::npos) << error;
  EXPECT_NE(error.find("--display headless"), std::string::npos) << error;
  KmsDisplaySettings named;
  named.device = "/dev/dri/card7";
  KmsDisplay missing(named);
  EXPECT_FALSE(missing.open(640, 480, error));
  EXPECT_NE(error.find("/dev/dri/card7"), std::string::npos) << error;

  const testing::CommandResult result = run("run --display kms --frames 1 --out " + (dir_ / "out").string());
  EXPECT_EQ(result.exit_status, 1) << result.stderr_text;
  EXPECT_EQ(std::count(result.stderr_text.begin(), result.stderr_text.end(), '\n'), 1) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("--display headless"), std::string::npos) << result.stderr_text;
}

}  // namespace
}  // namespace probelight
