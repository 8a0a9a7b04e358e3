// `probelight print-tag` through the binary: the sheet it writes is read
// back (OpenCV) and libapriltag finds the rig's tag in it (at the
// sheet's resolution, as a camera would see the print square on), with
// the black square exactly tag_size across at the resolution the PNG says
// it has (pHYs): to a pixel, the rasterisation's rounding at each edge.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binary_test_support.hpp"
#include "tracking/tag_detector.hpp"

namespace probelight {
namespace {

class PrintTag : public testing::BinaryTest {
 protected:
  PrintTag() : BinaryTest("print_tag") {}
};

// The PNG's pHYs pixels per metre (x), 0 when it has none.
std::uint32_t pngPixelsPerMetre(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto be32 = [&](std::size_t at) {
    return (std::uint32_t{b[at]} << 24) | (std::uint32_t{b[at + 1]} << 16) | (std::uint32_t{b[at + 2]} << 8) | b[at + 3];
  };
  for (std::size_t at = 8; at + 12 <= b.size();) {
    const std::uint32_t length = be32(at);
    if (std::string(b.begin() + static_cast<long>(at) + 4, b.begin() + static_cast<long>(at) + 8) == "pHYs")
      return be32(at + 8);
    at += 12 + length;
  }
  return 0;
}

TEST_F(PrintTag, TheSheetHoldsTheRigsTagToScale) {
  const std::filesystem::path rig = dir_ / "rig.yaml", sheet = dir_ / "tag.png";
  std::ofstream(rig) << "%YAML:1.0\n---\ntag_family: tag36h11\ntag_id: 7\ntag_size: 0.080\nprobe_center: [0.12, 0, 0.03]\n"
                        "probe_radius: 0.03\n";
  const testing::CommandResult result = run("print-tag --rig " + rig.string() + " --dpi 150 --out " + sheet.string());
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  const double pixels_per_metre = 150.0 / 0.0254;
  EXPECT_EQ(pngPixelsPerMetre(sheet), static_cast<std::uint32_t>(std::lround(pixels_per_metre)));
  const cv::Mat image = cv::imread(sheet.string(), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(image.empty());
  // A4 at 150 dpi.
  EXPECT_EQ(image.cols, static_cast<int>(std::lround(0.210 * pixels_per_metre)));
  EXPECT_EQ(image.rows, static_cast<int>(std::lround(0.297 * pixels_per_metre)));
  tracking::TagDetectorSettings settings;
  settings.family = "tag36h11";
  settings.quad_decimate = 1.0f;
  tracking::TagDetector detector(settings);
  const std::vector<tracking::TagDetection> found =
      detector.detect(image.ptr<std::uint8_t>(), image.cols, image.rows, static_cast<int>(image.step));
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].id, 7);
  EXPECT_EQ(found[0].hamming, 0);
  // The black square: the bounding box of the dark pixels in the tag's
  // upper part of the sheet (the scale bar and text are below it).
  const cv::Mat upper = image(cv::Rect(0, 0, image.cols, static_cast<int>(0.015 * pixels_per_metre + 0.1 * pixels_per_metre)));
  const cv::Rect black = cv::boundingRect(upper < 128);
  const double expected_px = 0.080 * pixels_per_metre;
  std::printf("[ print-tag ] black square %d x %d px, expected %.2f\n", black.width, black.height, expected_px);
  EXPECT_NEAR(black.width, expected_px, 1.0);
  EXPECT_NEAR(black.height, expected_px, 1.0);
  // The detected corners span the same square, to the detector's fraction of a pixel.
  EXPECT_NEAR(glm::length(found[0].corners_px[1] - found[0].corners_px[0]), expected_px, 1.5);
}

TEST_F(PrintTag, ABadRigFileOrFlagIsOneLineAndExit2) {
  const std::filesystem::path rig = dir_ / "rig.yaml";
  std::ofstream(rig) << "%YAML:1.0\n---\ntag_family: tag99h99\ntag_id: 0\ntag_size: 0.1\n";
  const testing::CommandResult bad_rig = run("print-tag --rig " + rig.string() + " --out " + (dir_ / "t.png").string());
  EXPECT_EQ(bad_rig.exit_status, 2);
  EXPECT_EQ(testing::countOccurrences(bad_rig.stderr_text, "\n"), 1u) << bad_rig.stderr_text;
  EXPECT_NE(bad_rig.stderr_text.find("tag_family"), std::string::npos) << bad_rig.stderr_text;
  const testing::CommandResult bad_dpi = run("print-tag --dpi 10 --out " + (dir_ / "t.png").string());
  EXPECT_EQ(bad_dpi.exit_status, 2);
  EXPECT_NE(bad_dpi.stderr_text.find("--dpi"), std::string::npos) << bad_dpi.stderr_text;
  const testing::CommandResult no_out = run("print-tag");
  EXPECT_EQ(no_out.exit_status, 2);
  EXPECT_NE(no_out.stderr_text.find("--out"), std::string::npos) << no_out.stderr_text;
}

}  // namespace
}  // namespace probelight
