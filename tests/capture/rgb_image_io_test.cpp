// readImageFile: files from users are checked before OpenCV decodes them.
// Each case is a file that OpenCV alone hangs on, over-allocates for, or
// decodes without complaint although it is broken.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "capture/rgb_image_io.hpp"

namespace probelight {
namespace {

namespace fs = std::filesystem;

class ReadImageFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) / ("probelight_read_image_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A 64x48 picture with edges and noise, encoded by OpenCV.
  static std::vector<std::uint8_t> encoded(const std::string& extension) {
    cv::Mat image(48, 64, CV_8UC3);
    cv::randu(image, 0, 255);
    image(cv::Rect(0, 0, 20, 48)).setTo(cv::Scalar(255, 255, 255));
    std::vector<std::uint8_t> bytes;
    EXPECT_TRUE(cv::imencode(extension, image, bytes));
    return bytes;
  }
  fs::path write(const std::string& name, const std::vector<std::uint8_t>& bytes) const {
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                                static_cast<std::streamsize>(bytes.size()));
    return path;
  }
  static std::string why(const fs::path& path) {
    std::string reason;
    const cv::Mat image = readImageFile(path.string(), cv::IMREAD_COLOR, &reason);
    EXPECT_TRUE(image.empty()) << path;
    return reason;
  }

  fs::path dir_;
};

TEST_F(ReadImageFile, WholePngJpegBmpAndPpmFilesAreRead) {
  for (const std::string extension : {".png", ".jpg", ".bmp", ".ppm"}) {
    const fs::path path = write("whole" + extension, encoded(extension));
    std::string reason;
    const cv::Mat image = readImageFile(path.string(), cv::IMREAD_COLOR, &reason);
    EXPECT_EQ(image.cols, 64) << extension << ": " << reason;
    EXPECT_EQ(image.rows, 48) << extension;
  }
}

// Only the formats whose headers readImageFile checks reach OpenCV: a damaged
// DICOM file (found by fuzz/image_file_fuzzer.cpp) made GDCM, under OpenCV,
// abort the process on an assert; TIFF and WebP, which OpenCV also decodes,
// are refused the same way, before any decoder sees them.
TEST_F(ReadImageFile, FormatsOtherThanPngJpegBmpAndPnmAreRefusedBeforeDecoding) {
  const std::vector<std::uint8_t> dicom = {'!', '!', 0x89, 0x16, 0, 0, 0, 0, 0, 0, 0xc1, 0xba, 'D', 'I', 'C', 'M'};
  const std::vector<std::uint8_t> tiff = {'I', 'I', '*', 0, 8, 0, 0, 0, 0, 0};
  const std::vector<std::uint8_t> webp = {'R', 'I', 'F', 'F', 4, 0, 0, 0, 'W', 'E', 'B', 'P'};
  for (const auto& [name, bytes] : {std::pair{"dicom.png", dicom}, std::pair{"frame.tif", tiff}, std::pair{"frame.webp", webp}}) {
    std::string reason;
    EXPECT_TRUE(readImageFile(write(name, bytes).string(), cv::IMREAD_COLOR, &reason).empty()) << name;
    EXPECT_NE(reason.find("not a PNG, JPEG, BMP or PNM image"), std::string::npos) << name << ": " << reason;
  }
}

// OpenCV decodes both with the missing rows filled in; only libjpeg prints a
// warning ("Premature end of JPEG file").
TEST_F(ReadImageFile, APngOrJpegCutShortIsRefused) {
  for (const std::string extension : {".png", ".jpg"}) {
    std::vector<std::uint8_t> bytes = encoded(extension);
    bytes.resize(bytes.size() * 9 / 10);
    const fs::path path = write("cut" + extension, bytes);
    EXPECT_NE(why(path).find("cut short"), std::string::npos) << extension << ": " << why(path);
  }
}

// A FIFO would block the read until a writer comes, forever.
TEST_F(ReadImageFile, AFifoIsRefusedWithoutWaitingForAWriter) {
  const fs::path fifo = dir_ / "frame.png";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_NE(why(fifo).find("not a regular file"), std::string::npos) << why(fifo);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  EXPECT_NE(why(dir_).find("folder"), std::string::npos) << why(dir_);
  EXPECT_EQ(why(dir_ / "nowhere.png"), "no such file");
  EXPECT_EQ(why(write("empty.png", {})), "an empty file");
}

// Headers claiming 9000 px on a side: within OpenCV's own limit (2^30
// pixels), which would allocate 243 MB and decode; refused from the header.
TEST_F(ReadImageFile, AHeaderClaimingASideAbove8192IsRefusedBeforeDecoding) {
  std::vector<std::uint8_t> png = encoded(".png");
  png[16] = 0, png[17] = 0, png[18] = 0x23, png[19] = 0x28;  // IHDR width 9000
  EXPECT_NE(why(write("wide.png", png)).find("says 9000x48"), std::string::npos) << why(write("wide.png", png));

  std::vector<std::uint8_t> bmp = encoded(".bmp");
  bmp[22] = 0x28, bmp[23] = 0x23, bmp[24] = 0, bmp[25] = 0;  // height 9000
  EXPECT_NE(why(write("tall.bmp", bmp)).find("says 64x9000"), std::string::npos) << why(write("tall.bmp", bmp));

  const std::string ppm_header = "P6\n# a comment\n9000 99999999999999999999999\n255\n";
  const fs::path ppm = write("huge.ppm", std::vector<std::uint8_t>(ppm_header.begin(), ppm_header.end()));
  EXPECT_NE(why(ppm).find("above the 8192 px limit"), std::string::npos) << why(ppm);
  // OpenCV skips any byte that is not a digit between the numbers, so the
  // check does too (fuzz/image_file_fuzzer.cpp: this header made OpenCV
  // allocate 2.8 GB while the check read its height as 0).
  // And the byte that ends a number is consumed whatever it is, a '#' too.
  for (const std::string& odd_separator : {std::string("P6\n3533\x10" "266777\n255\n"), std::string("P6\n3533#266777(255\n")}) {
    const fs::path separated = write("separated.ppm", std::vector<std::uint8_t>(odd_separator.begin(), odd_separator.end()));
    EXPECT_NE(why(separated).find("says 3533x266777"), std::string::npos) << why(separated);
  }
  // A comment of its own still ends at its line.
  const std::string commented = "P6\n# 99999 99999\n3 2\n255\n";
  const fs::path small = write("commented.ppm", std::vector<std::uint8_t>(commented.begin(), commented.end()));
  EXPECT_EQ(why(small).find("above the 8192 px limit"), std::string::npos) << why(small);

  // JPEG: the frame header's height and width (big-endian after the precision byte).
  std::vector<std::uint8_t> jpeg = encoded(".jpg");
  bool patched = false;
  for (std::size_t i = 2; i + 9 < jpeg.size() && !patched; ++i)
    if (jpeg[i] == 0xFF && jpeg[i + 1] == 0xC0) {
      jpeg[i + 5] = 0x23, jpeg[i + 6] = 0x28;  // height 9000
      patched = true;
    }
  ASSERT_TRUE(patched);
  EXPECT_NE(why(write("tall.jpg", jpeg)).find("says 64x9000"), std::string::npos) << why(write("tall.jpg", jpeg));
}

// writeRgbPng is lossless and in probelight's RGB order: every byte of an
// image with noise, sharp edges and odd dimensions (each row filtered
// against the one above) comes back through an independent decoder
// (OpenCV's), channels swapped to its BGR.
TEST(WriteRgbPng, EveryByteComesBackThroughOpenCvsDecoder) {
  ImageRGB8 image;
  image.resize(37, 23);
  std::uint32_t state = 12345;
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    state = state * 1664525u + 1013904223u;
    image.pixels[i] = (i / 3) % 37 < 11 ? static_cast<std::uint8_t>(i % 3 == 0 ? 255 : 0)
                                        : static_cast<std::uint8_t>(state >> 24);
  }
  const std::string path = ::testing::TempDir() + "/probelight-write-rgb-png.png";
  std::string error;
  ASSERT_TRUE(writeRgbPng(path, image, error)) << error;
  const cv::Mat back = cv::imread(path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(back.type(), CV_8UC3);
  ASSERT_EQ(back.cols, 37);
  ASSERT_EQ(back.rows, 23);
  int mismatches = 0;
  for (int y = 0; y < back.rows; ++y)
    for (int x = 0; x < back.cols; ++x)
      for (int c = 0; c < 3; ++c)
        mismatches += back.at<cv::Vec3b>(y, x)[2 - c] != image.pixels[(static_cast<std::size_t>(y) * 37 + x) * 3 + c];
  EXPECT_EQ(mismatches, 0);
  // And readImageFile's own checks pass on what it wrote.
  std::string reason;
  EXPECT_FALSE(readImageFile(path, cv::IMREAD_COLOR, &reason).empty()) << reason;
  fs::remove(path);
}

TEST(WriteRgbPng, AnEmptyImageOrAnUnwritablePathIsAnErrorNamingTheFile) {
  std::string error;
  EXPECT_FALSE(writeRgbPng(::testing::TempDir() + "/empty.png", ImageRGB8{}, error));
  EXPECT_NE(error.find("empty.png"), std::string::npos) << error;
  const std::string folder = ::testing::TempDir();  // a folder cannot be opened for writing
  EXPECT_FALSE(writeRgbPng(folder, ImageRGB8{}, error));
  ImageRGB8 one;
  one.resize(1, 1);
  EXPECT_FALSE(writeRgbPng(folder, one, error));
  EXPECT_NE(error.find(folder), std::string::npos) << error;
}

}  // namespace
}  // namespace probelight
