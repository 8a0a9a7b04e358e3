// formatCameraList: what `probelight cameras` prints, from listings made
// here (libcamera's own listing is checked in the board VM, on vimc).
#include <gtest/gtest.h>

#include <sstream>

#include "capture/camera_list.hpp"

namespace probelight {
namespace {

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

TEST(CameraList, NoCameraIsOneLineSayingWhatToCheck) {
  const std::vector<std::string> text = lines(formatCameraList({}));
  ASSERT_EQ(text.size(), 1u);
  EXPECT_NE(text[0].find("found no camera"), std::string::npos);
  EXPECT_NE(text[0].find("--source sim"), std::string::npos);
}

TEST(CameraList, EachCameraWithItsIdFormatsAndSizes) {
  CameraListing webcam;
  webcam.id = "\\_SB_.PCI0.XHC_.RHUB.HS05-5:1.0-04f2:b6dd";
  webcam.model = "Integrated Camera";
  webcam.location = "external";
  // Listed out of order: the text puts them smallest to largest.
  webcam.formats.push_back({"MJPEG", {{1280, 720}, {640, 480}, {320, 240}}, {320, 240, 1280, 720}});
  webcam.formats.push_back({"YUYV", {}, {160, 120, 640, 480, 2, 2}});  // a range, no discrete sizes
  CameraListing many;
  many.id = "/base/many";
  for (int i = 1; i <= 12; ++i) many.formats.resize(1), many.formats[0].sizes_px.emplace_back(100 * i, 50 * i);
  many.formats[0].pixel_format = "NV12";
  const std::vector<std::string> text = lines(formatCameraList({webcam, many}, 4));
  ASSERT_EQ(text.size(), 9u) << formatCameraList({webcam, many}, 4);
  EXPECT_EQ(text[0], "2 cameras:");
  EXPECT_EQ(text[1], "0: 'Integrated Camera', external");
  EXPECT_EQ(text[2], "   id: " + webcam.id);
  EXPECT_EQ(text[3], "   MJPEG: 320x240 640x480 1280x720");
  EXPECT_EQ(text[4], "   YUYV: 160x120 to 640x480, in steps of 2x2 (the camera may round a size; run says the nearest it takes)");
  EXPECT_EQ(text[5], "1: (no model given)");
  EXPECT_EQ(text[6], "   id: /base/many");
  // At most 4 shown: the three smallest, "...", the largest.
  EXPECT_EQ(text[7], "   NV12: 100x50 200x100 300x150 ... 1200x600");
  EXPECT_NE(text[8].find("--camera-id"), std::string::npos);
}

}  // namespace
}  // namespace probelight
