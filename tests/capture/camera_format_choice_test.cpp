// Which format and size the libcamera source asks a camera for (issue 17):
// the formats real cameras list (a Pi camera's ISP, a USB webcam, the
// kernel's vimc), as libcamera names them.
#include <gtest/gtest.h>

#include "capture/camera_format_choice.hpp"

namespace probelight {
namespace {

TEST(CameraFormatChoice, AutoTakesTheCheapestFormatTheCameraOffers) {
  std::string error;
  // A Pi camera through its ISP.
  EXPECT_EQ(chooseCameraFormat({"XBGR8888", "RGB888", "NV12", "YUV420"}, "auto", "imx708", error), CameraFormat::kYuv420);
  // A USB webcam (uvcvideo).
  EXPECT_EQ(chooseCameraFormat({"MJPEG", "YUYV"}, "auto", "uvc", error), CameraFormat::kYuyv);
  EXPECT_EQ(chooseCameraFormat({"MJPEG"}, "auto", "uvc", error), CameraFormat::kMjpeg);
  // vimc's sensor B through its scaler.
  EXPECT_EQ(chooseCameraFormat({"RGB888", "BGR888"}, "auto", "vimc", error), CameraFormat::kBgr888);
  EXPECT_EQ(chooseCameraFormat({"XRGB8888"}, "auto", "vimc", error), CameraFormat::kXrgb8888);
  EXPECT_FALSE(chooseCameraFormat({"SRGGB10", "R8"}, "auto", "raw-only", error));
  EXPECT_EQ(error, "camera: raw-only offers SRGGB10, R8, none of the formats probelight reads "
                   "(YUV420, NV12, YUYV, BGR888, RGB888, XRGB8888, MJPEG)");
}

TEST(CameraFormatChoice, AnAskedForFormatIsTakenOnlyWhenOffered) {
  std::string error;
  EXPECT_EQ(chooseCameraFormat({"YUV420", "NV12"}, "nv12", "imx708", error), CameraFormat::kNv12);
  EXPECT_EQ(chooseCameraFormat({"MJPEG", "YUYV"}, "mjpeg", "uvc", error), CameraFormat::kMjpeg);
  EXPECT_FALSE(chooseCameraFormat({"BGR888", "RGB888"}, "yuv420", "platform/vimc.0 Sensor B", error));
  EXPECT_EQ(error, "camera: platform/vimc.0 Sensor B does not offer YUV420 (camera.pixel_format yuv420); it offers "
                   "BGR888, RGB888: set camera.pixel_format to auto or to one of those");
  EXPECT_FALSE(chooseCameraFormat({}, "auto", "empty", error));
  EXPECT_NE(error.find("offers nothing"), std::string::npos) << error;
}

TEST(CameraFormatChoice, EveryConfigNameMapsToALayoutTheGpuConverts) {
  const std::vector<std::string> names = cameraFormatConfigNames();
  EXPECT_EQ(names.front(), "auto");
  EXPECT_EQ(names.size(), cameraFormats().size() + 1);
  EXPECT_EQ(cameraFormatInfo(CameraFormat::kMjpeg).layout, PixelLayout::kRgb8);  // decoded on the CPU
  for (const CameraFormatInfo& info : cameraFormats()) {
    if (info.format != CameraFormat::kMjpeg) {
      EXPECT_STREQ(layoutName(info.layout), info.libcamera_name);
    }
  }
}

TEST(CameraFormatChoice, TheNearestSizeFromAListOrASteppedRange) {
  OfferedSizes webcam;
  webcam.listed = {{640, 480}, {1280, 720}, {1920, 1080}, {320, 240}};
  EXPECT_EQ(*nearestOfferedSize(webcam, {1280, 720}), (FrameSizePx{1280, 720}));
  EXPECT_EQ(*nearestOfferedSize(webcam, {1296, 972}), (FrameSizePx{1280, 720}));
  EXPECT_EQ(*nearestOfferedSize(webcam, {600, 450}), (FrameSizePx{640, 480}));
  OfferedSizes vimc;  // vimc's scaler: 16x16 to 4096x2160 in steps of 1
  vimc.range_min = FrameSizePx{16, 16};
  vimc.range_max = FrameSizePx{4096, 2160};
  EXPECT_EQ(*nearestOfferedSize(vimc, {1296, 972}), (FrameSizePx{1296, 972}));
  EXPECT_EQ(*nearestOfferedSize(vimc, {8000, 4000}), (FrameSizePx{4096, 2160}));
  OfferedSizes stepped;
  stepped.range_min = FrameSizePx{32, 32};
  stepped.range_max = FrameSizePx{1920, 1080};
  stepped.width_step = 16;
  stepped.height_step = 8;
  EXPECT_EQ(*nearestOfferedSize(stepped, {1001, 701}), (FrameSizePx{1008, 704}));
  EXPECT_FALSE(nearestOfferedSize(OfferedSizes{}, {640, 480}));
}

TEST(CameraFormatChoice, ASizeOtherThanTheCalibratedOneIsRefusedNamingBoth) {
  EXPECT_EQ(sizeMismatchProblem("uvc", "YUYV", {640, 480}, {640, 480}), "");
  EXPECT_EQ(sizeMismatchProblem("uvc", "YUYV", {1296, 972}, {1280, 720}),
            "camera: uvc cannot stream YUYV at camera.yaml's 1296x972; the nearest it offers is 1280x720: calibrate "
            "the camera at 1280x720 (probelight calibrate-camera) or use a camera.yaml made at a size it offers");
}

}  // namespace
}  // namespace probelight
