// The libcamera source against libcamera's own CameraManager on a machine
// with no camera: a clear error naming what was looked for and the usual
// causes; and `run --source libcamera` fails with that line.
#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "binary_test_support.hpp"
#include "capture/libcamera_source.hpp"
#include "config/camera_file.hpp"
#include "config/rig_file.hpp"

namespace probelight {
namespace {

bool machineHasCameraDevices() { return std::filesystem::exists("/dev/media0") || std::filesystem::exists("/dev/video0"); }

TEST(LibcameraSource, NoCameraIsAClearErrorWithTheUsualCauses) {
  if (machineHasCameraDevices()) GTEST_SKIP() << "this machine has camera devices";
  ::setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", 0);
  std::string error;
  {
    LibcameraSource source({});
    EXPECT_FALSE(source.start(error));
    for (const char* cause : {"found no camera", "ribbon cable", "camera_auto_detect=1", "/dev/media*", "/dev/dma_heap"})
      EXPECT_NE(error.find(cause), std::string::npos) << cause << ": " << error;
    // A retry on the same source (the kiosk's reconnection) starts a fresh
    // camera manager: libcamera allows one per process at a time.
    EXPECT_FALSE(source.start(error));
    EXPECT_NE(error.find("found no camera"), std::string::npos) << error;
  }
  LibcameraSettings named;
  named.camera_id = "/base/soc/i2c0mux/i2c@1/imx708@1a";
  LibcameraSource wanted(named);
  EXPECT_FALSE(wanted.start(error));
  EXPECT_NE(error.find("found no camera"), std::string::npos) << error;
}

TEST(LibcameraSource, MessageListsTheCamerasThereAre) {
  EXPECT_EQ(noCameraMessage("imx999", {"imx708", "imx219"}), "camera: no camera 'imx999' (libcamera lists imx708, imx219)");
}

class LibcameraRun : public testing::BinaryTest {
 protected:
  LibcameraRun() : BinaryTest("libcamera") {}
};

TEST_F(LibcameraRun, RunWithoutACameraFailsWithOneLine) {
  if (machineHasCameraDevices()) GTEST_SKIP() << "this machine has camera devices";
  config::saveCameraFile((dir_ / "camera.yaml").string(), CameraIntrinsics{});
  config::saveRigFile((dir_ / "rig.yaml").string(), RigGeometry{});
  ::setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", 0);
  const testing::CommandResult result = run("run --source libcamera --calibration " + (dir_ / "camera.yaml").string() +
                                            " --rig " + (dir_ / "rig.yaml").string() + " --frames 1 --out " +
                                            (dir_ / "out").string());
  EXPECT_EQ(result.exit_status, 1) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("libcamera found no camera"), std::string::npos) << result.stderr_text;
  const testing::CommandResult missing_camera_file = run("run --source libcamera --frames 1");
  EXPECT_EQ(missing_camera_file.exit_status, 2);
  EXPECT_NE(missing_camera_file.stderr_text.find("--calibration camera.yaml"), std::string::npos);
}

}  // namespace
}  // namespace probelight
