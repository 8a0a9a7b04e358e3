// camera.yaml, rig.yaml and the typed reader behind them.
#include <algorithm>
#include <cmath>
#include <functional>

#include <gtest/gtest.h>

#include "config/camera_file.hpp"
#include "config/config_reader.hpp"
#include "config/rig_file.hpp"
#include "core/apriltag_families.hpp"
#include "test_support.hpp"

namespace probelight {
namespace {

using config::ConfigError;
using config::ConfigReader;
using testing::TempFolder;

// The shape of camera.yaml OpenCV's calibration sample writes (taken from its
// left01..14 reference calibration), extra keys and a 5x1 distortion included.
const char* const kOpenCvCalibration = R"(%YAML:1.0
---
calibration_time: "Thu 01 Jan 2015 10:00:00 CET"
nframes: 13
image_width: 640
image_height: 480
board_width: 9
board_height: 6
square_size: 2.5000000372529030e-02
aspectRatio: 1.
flags: 2
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 5.3591573396163199e+02, 0., 3.4228315473308373e+02, 0.,
       5.3591573396163199e+02, 2.3557082909788173e+02, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 5
   cols: 1
   dt: d
   data: [ -2.6637260909660682e-01, -3.8588898922304653e-02,
       1.7831947042852964e-03, -2.8122100441115472e-04,
       2.3839153080878486e-01 ]
avg_reprojection_error: 3.9259098975581364e-01
per_view_reprojection_errors: !!opencv-matrix
   rows: 2
   cols: 1
   dt: f
   data: [ 1.92965463e-01, 1.18204820e+00 ]
)";

const char* const kGoodRig = R"(tag_family: tag36h11
tag_id: 7
tag_size: 0.08
probe_center: [0.1, -0.02, 0.03]
probe_radius: 0.03
)";

std::string cameraFileWith(const std::string& matrix_data, const std::string& distortion_block,
                           const std::string& extra = "") {
  return "image_width: 640\nimage_height: 480\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
         "   data: [" + matrix_data + "]\n" + distortion_block + extra;
}
const char* const kPlainMatrix = "600., 0., 320., 0., 600., 240., 0., 0., 1.";
const char* const kDistortion1x5 =
    "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [0.1, -0.2, 0.001, 0.002, 0.05]\n";

// Every config error must be one line starting with the file and, where a
// field is at fault, naming it.
void expectConfigError(const std::function<void()>& load, const std::string& path, const std::string& field,
                       const std::string& expected_words = "") {
  try {
    load();
    ADD_FAILURE() << "expected a ConfigError for " << path << " field '" << field << "'";
  } catch (const ConfigError& error) {
    std::string message = error.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
    if (!field.empty()) {
      EXPECT_NE(message.find("field '" + field + "'"), std::string::npos) << message;
    }
    if (!expected_words.empty()) {
      EXPECT_NE(message.find(expected_words), std::string::npos) << message;
    }
  }
}

TEST(CameraFile, LoadsWhatOpenCvCalibrationWrites) {
  TempFolder folder;
  CameraIntrinsics camera = config::loadCameraFile(folder.write("camera.yaml", kOpenCvCalibration));
  EXPECT_EQ(camera.width_px, 640);
  EXPECT_EQ(camera.height_px, 480);
  // Values are parsed from 17-digit decimals, so they must match to the last bit or two.
  EXPECT_DOUBLE_EQ(camera.fx_px, 535.91573396163199);
  EXPECT_DOUBLE_EQ(camera.fy_px, 535.91573396163199);
  EXPECT_DOUBLE_EQ(camera.cx_px, 342.28315473308373);
  EXPECT_DOUBLE_EQ(camera.cy_px, 235.57082909788173);
  EXPECT_DOUBLE_EQ(camera.distortion[0], -0.26637260909660682);
  EXPECT_DOUBLE_EQ(camera.distortion[4], 0.23839153080878486);
}

TEST(CameraFile, AcceptsFourCoefficientsAndAFlatListWithoutHeader) {
  TempFolder folder;
  std::string path = folder.write("camera.yaml", cameraFileWith(kPlainMatrix, "distortion_coefficients: [0.1, -0.2, 0.001, 0.002]\n"));
  CameraIntrinsics camera = config::loadCameraFile(path);
  EXPECT_DOUBLE_EQ(camera.distortion[1], -0.2);
  EXPECT_EQ(camera.distortion[4], 0.0);  // k3 absent means zero
}

TEST(CameraFile, BoardTemplateLoads) {
  CameraIntrinsics camera = config::loadCameraFile(testing::testDataPath("../../board/camera.yaml"));
  EXPECT_EQ(camera.width_px, 640);
  EXPECT_EQ(camera.height_px, 480);
  RigGeometry rig = config::loadRigFile(testing::testDataPath("../../board/rig.yaml"));
  EXPECT_EQ(rig.tag_family, "tag36h11");
  // The ball rests on the ground in the template.
  EXPECT_DOUBLE_EQ(rig.probe_center_w.z, rig.probe_radius_m);
}

TEST(CameraFile, SaveThenLoadRoundTrips) {
  TempFolder folder;
  CameraIntrinsics original;
  original.width_px = 1296;
  original.height_px = 972;
  original.fx_px = 1013.2571938475;
  original.fy_px = 1011.0000000001;
  original.cx_px = 651.123456789;
  original.cy_px = 480.987654321;
  original.distortion = {0.123456789, -0.3456, 1.5e-4, -2.5e-4, 0.098765};
  original.lens_position_dioptres = 2.71828;
  std::string path = folder.file("saved.yaml");
  config::saveCameraFile(path, original);
  CameraIntrinsics loaded = config::loadCameraFile(path);
  EXPECT_EQ(loaded.width_px, original.width_px);
  EXPECT_EQ(loaded.height_px, original.height_px);
  // OpenCV writes doubles with 17 significant digits, which round-trips exactly.
  EXPECT_EQ(loaded.fx_px, original.fx_px);
  EXPECT_EQ(loaded.fy_px, original.fy_px);
  EXPECT_EQ(loaded.cx_px, original.cx_px);
  EXPECT_EQ(loaded.cy_px, original.cy_px);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(loaded.distortion[i], original.distortion[i]) << "coefficient " << i;
  EXPECT_EQ(loaded.lens_position_dioptres, original.lens_position_dioptres);
  // Without a lens position, none is written (the file OpenCV's tools read).
  original.lens_position_dioptres.reset();
  config::saveCameraFile(path, original);
  EXPECT_FALSE(config::loadCameraFile(path).lens_position_dioptres.has_value());
}

// The lens position the intrinsics hold at (issue 48): optional; present,
// it must be a focus a lens can have, in [0, 100] dioptres.
TEST(CameraFile, LensPositionIsOptionalAndABadOneIsOneLineNamingTheField) {
  TempFolder folder;
  EXPECT_FALSE(config::loadCameraFile(folder.write("none.yaml", cameraFileWith(kPlainMatrix, kDistortion1x5)))
                   .lens_position_dioptres.has_value());
  for (const double good : {0.0, 2.5, 100.0}) {
    const std::string path = folder.write("good.yaml", cameraFileWith(kPlainMatrix, kDistortion1x5,
                                                                      "lens_position_dioptres: " +
                                                                          config::formatNumber(good) + "\n"));
    EXPECT_EQ(config::loadCameraFile(path).lens_position_dioptres, good);
  }
  const char* const field = "lens_position_dioptres";
  for (const auto& [value, expected] : std::vector<std::pair<std::string, std::string>>{
           {"-0.5", "-0.5 is out of range, must be in [0, 100]"},
           {"100.5", "100.5 is out of range, must be in [0, 100]"},
           {"500", "500 is out of range"},  // a focus distance in millimetres
           {".nan", "finite"},
           {".inf", "finite"},
           {"near", "expected a number"},
           {"[2.5, 3]", "expected a number"}}) {
    SCOPED_TRACE(value);
    const std::string path = folder.write("bad.yaml", cameraFileWith(kPlainMatrix, kDistortion1x5,
                                                                     std::string(field) + ": " + value + "\n"));
    expectConfigError([&] { config::loadCameraFile(path); }, path, field, expected);
  }
  // Intrinsics from elsewhere (a calibration run) are checked the same way.
  CameraIntrinsics camera;
  camera.lens_position_dioptres = -1.0;
  expectConfigError([&] { config::saveCameraFile(folder.file("bad_save.yaml"), camera); }, folder.file("bad_save.yaml"),
                    field, "out of range");
}

TEST(CameraFile, RejectsEachMalformedCaseWithOneLineNamingFileAndField) {
  TempFolder folder;
  auto load = [](const std::string& path) { return [path] { config::loadCameraFile(path); }; };

  std::string missing = folder.file("does-not-exist.yaml");
  expectConfigError(load(missing), missing, "", "cannot open");

  std::string malformed = folder.write("malformed.yaml", "image_width: 640\nimage_height: [480, 1\ncamera_matrix: 3\n");
  expectConfigError(load(malformed), malformed, "", "malformed YAML at line");

  std::string empty = folder.write("empty.yaml", "\n\n");
  expectConfigError(load(empty), empty, "", "empty");

  std::string no_matrix = folder.write("no_matrix.yaml", "image_width: 640\nimage_height: 480\n" + std::string(kDistortion1x5));
  expectConfigError(load(no_matrix), no_matrix, "camera_matrix", "missing");

  std::string text_width = folder.write("text_width.yaml", cameraFileWith(kPlainMatrix, kDistortion1x5));
  {
    std::string text = cameraFileWith(kPlainMatrix, kDistortion1x5);
    text.replace(text.find("640"), 3, "wide");
    folder.write("text_width.yaml", text);
  }
  expectConfigError(load(text_width), text_width, "image_width", "expected an integer");

  std::string negative_fx = folder.write("negative_fx.yaml", cameraFileWith("-600., 0., 320., 0., 600., 240., 0., 0., 1.", kDistortion1x5));
  expectConfigError(load(negative_fx), negative_fx, "camera_matrix", "out of range");

  std::string outside = folder.write("outside.yaml", cameraFileWith("600., 0., 700., 0., 600., 240., 0., 0., 1.", kDistortion1x5));
  expectConfigError(load(outside), outside, "camera_matrix", "principal point");

  std::string non_finite = folder.write("non_finite.yaml", cameraFileWith("600., 0., 320., 0., .nan, 240., 0., 0., 1.", kDistortion1x5));
  expectConfigError(load(non_finite), non_finite, "camera_matrix", "finite");

  std::string wrong_shape = folder.write("wrong_shape.yaml", cameraFileWith(kPlainMatrix, "distortion_coefficients: !!opencv-matrix\n   rows: 2\n   cols: 3\n   dt: d\n   data: [0, 0, 0, 0, 0, 0]\n"));
  expectConfigError(load(wrong_shape), wrong_shape, "distortion_coefficients", "1xN");

  std::string eight_terms = folder.write("eight_terms.yaml", cameraFileWith(kPlainMatrix, "distortion_coefficients: [0.1, 0, 0, 0, 0, 0.3, 0, 0]\n"));
  expectConfigError(load(eight_terms), eight_terms, "distortion_coefficients", "only k1 k2 p1 p2 k3");

  std::string typo = folder.write("typo.yaml", cameraFileWith(kPlainMatrix, kDistortion1x5, "image_heigth: 480\n"));
  expectConfigError(load(typo), typo, "image_heigth", "unknown field");

  std::string fisheye = folder.write("fisheye.yaml", cameraFileWith(kPlainMatrix, kDistortion1x5, "fisheye_model: 1\n"));
  expectConfigError(load(fisheye), fisheye, "fisheye_model", "not supported");

  // Implausible values that once passed and crashed later (issue 15, D4, D7,
  // D8, D19): a 20000x15000 frame the simulator would allocate 21 GB for, a
  // focal length of 1e-300 px, a tangential term of 1000, k1 of 1e308.
  std::string huge = folder.write("huge.yaml", [] {
    std::string text = cameraFileWith("600., 0., 320., 0., 600., 240., 0., 0., 1.", kDistortion1x5);
    text.replace(text.find("image_width: 640"), 16, "image_width: 20000");
    return text;
  }());
  expectConfigError(load(huge), huge, "image_width", "[1, 8192]");
  std::string tiny_focal = folder.write("tiny_focal.yaml", cameraFileWith("1e-300, 0., 320., 0., 600., 240., 0., 0., 1.", kDistortion1x5));
  expectConfigError(load(tiny_focal), tiny_focal, "camera_matrix", "[64, 32000] px for a 640x480 image");
  std::string long_focal = folder.write("long_focal.yaml", cameraFileWith("600., 0., 320., 0., 1e308, 240., 0., 0., 1.", kDistortion1x5));
  expectConfigError(load(long_focal), long_focal, "camera_matrix", "out of range");
  std::string tangential = folder.write("tangential.yaml", cameraFileWith(kPlainMatrix, "distortion_coefficients: [0.1, 0, 1000, 0, 0]\n"));
  expectConfigError(load(tangential), tangential, "distortion_coefficients", "p1 = 1000 is out of range");
  std::string radial = folder.write("radial.yaml", cameraFileWith(kPlainMatrix, "distortion_coefficients: [1e308, 0, 0, 0, 0]\n"));
  expectConfigError(load(radial), radial, "distortion_coefficients", "k1");
}

// OpenCV reads the first of duplicate matrix keys, ignores unknown ones
// and saturates dt: u (600 became 255, analysed with exit 0); each is now a
// line naming the file and the matrix (issue 15, D8, D9).
TEST(CameraFile, DuplicateOrUnknownMatrixKeysAndIntegerTypesAreRefused) {
  TempFolder folder;
  auto load = [](const std::string& path) { return [path] { config::loadCameraFile(path); }; };
  const std::string good = cameraFileWith(kPlainMatrix, kDistortion1x5);
  const std::string matrix_start = "camera_matrix: !!opencv-matrix\n";
  const std::pair<std::string, std::string> cases[] = {
      {"   rows: 3\n", "key 'rows' appears twice"},
      {"   data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n", "key 'data' appears twice"},
      {"   step: 4\n", "unknown key 'step'"},
  };
  int index = 0;
  for (const auto& [extra_line, says] : cases) {
    std::string text = good;
    // After the matrix's own data line, inside its block.
    const std::size_t data_end = text.find("\n", text.find("   data:", text.find(matrix_start))) + 1;
    text.insert(data_end, extra_line);
    const std::string path = folder.write("dup" + std::to_string(index++) + ".yaml", text);
    expectConfigError(load(path), path, "camera_matrix", says);
  }
  for (const char* type : {"u", "i", "s"}) {
    std::string text = good;
    text.replace(text.find("dt: d"), 5, std::string("dt: ") + type);
    const std::string path = folder.write(std::string("dt_") + type + ".yaml", text);
    expectConfigError(load(path), path, "camera_matrix", "would round or saturate");
  }
  // cv::read allocates rows x cols before reading data: a matrix saying
  // 65536 x 65536 asked for 32 GB (found by fuzz/camera_yaml_fuzzer.cpp).
  // The size must be what data holds, and rows and cols whole numbers.
  const std::pair<std::pair<std::string, std::string>, std::string> sizes[] = {
      {{"rows: 3", "rows: 65536"}, "says 65536x3 but its data holds 9 numbers"},
      {{"cols: 3", "cols: 0"}, "says 3x0 but its data holds 9 numbers"},
      {{"cols: 3", "cols: three"}, "must be whole numbers"},
  };
  for (const auto& [edit, says] : sizes) {
    std::string text = good;
    text.replace(text.find(edit.first), edit.first.size(), edit.second);
    const std::string path = folder.write("size" + std::to_string(index++) + ".yaml", text);
    expectConfigError(load(path), path, "camera_matrix", says);
  }
  // dt: f, as OpenCV's own tools write some matrices, still loads.
  std::string as_float = good;
  as_float.replace(as_float.find("dt: d"), 5, "dt: f");
  EXPECT_NO_THROW(config::loadCameraFile(folder.write("dt_f.yaml", as_float)));
}

// k1 = -1.5 with a 600 px focal length: rd = r - 1.5 r^3 peaks at r = 0.47
// (rd 0.31), short of the frame's corner at rd 0.67, so the outer frame
// would be two directions at once. OpenCV's calibration sample's real
// lens (k1 -0.27, k3 0.24) rises all the way and loads (test above).
TEST(CameraFile, DistortionThatFoldsTheFrameIsRefused) {
  TempFolder folder;
  const std::string folding = folder.write(
      "fold.yaml", cameraFileWith(kPlainMatrix, "distortion_coefficients: [-1.5, 0.0, 0.0, 0.0, 0.0]\n"));
  expectConfigError([&] { config::loadCameraFile(folding); }, folding, "distortion_coefficients", "fold the image");
  CameraIntrinsics camera;
  camera.fx_px = camera.fy_px = 600.0;
  camera.cx_px = 319.5;
  camera.cy_px = 239.5;
  camera.distortion = {-1.5, 0.0, 0.0, 0.0, 0.0};
  const std::optional<double> fold = config::radialFoldInsideImage(camera);
  ASSERT_TRUE(fold);
  EXPECT_NEAR(*fold, std::sqrt(1.0 / 4.5), 0.668 / 4096.0 + 1e-9);  // rd' = 1 - 4.5 r^2 = 0
  // A weaker barrel peaks at r 1.05 with rd 0.70: past the corner's 0.67.
  camera.distortion = {-0.3, 0.0, 0.0, 0.0, 0.0};
  EXPECT_FALSE(config::radialFoldInsideImage(camera));
  // A fold past the corner does not matter: the frame never shows it.
  camera.distortion = {-0.6, 0.0, 0.0, 0.0, 0.0};  // peak at r 0.745, rd 0.50 < 0.67: folds inside
  EXPECT_TRUE(config::radialFoldInsideImage(camera));
  camera.fx_px = camera.fy_px = 1200.0;  // the corner at rd 0.33: reached before the peak
  EXPECT_FALSE(config::radialFoldInsideImage(camera));
}

TEST(RigFile, LoadsWithDefaultReflectance) {
  TempFolder folder;
  RigGeometry rig = config::loadRigFile(folder.write("rig.yaml", kGoodRig));
  EXPECT_EQ(rig.tag_family, "tag36h11");
  EXPECT_EQ(rig.tag_id, 7);
  EXPECT_DOUBLE_EQ(rig.tag_size_m, 0.08);
  EXPECT_DOUBLE_EQ(rig.probe_center_w.y, -0.02);
  EXPECT_DOUBLE_EQ(rig.probe_radius_m, 0.03);
  EXPECT_EQ(rig.probe_reflectance, 1.0);
}

TEST(RigFile, SaveThenLoadRoundTrips) {
  TempFolder folder;
  RigGeometry original;
  original.tag_family = "tagStandard41h12";
  original.tag_id = 1234;
  original.tag_size_m = 0.1234567;
  original.probe_center_w = {0.111111111, -0.0987654321, 0.0812345};
  original.probe_radius_m = 0.0312345;
  original.probe_reflectance = 0.72;
  original.post_radius_m = 0.0031234;
  original.post_albedo = 0.456;
  std::string path = folder.file("rig.yaml");
  config::saveRigFile(path, original);
  RigGeometry loaded = config::loadRigFile(path);
  EXPECT_EQ(loaded.tag_family, original.tag_family);
  EXPECT_EQ(loaded.tag_id, original.tag_id);
  // 17 significant digits on disk: exact round trip.
  EXPECT_EQ(loaded.tag_size_m, original.tag_size_m);
  EXPECT_EQ(loaded.probe_center_w, original.probe_center_w);
  EXPECT_EQ(loaded.probe_radius_m, original.probe_radius_m);
  EXPECT_EQ(loaded.probe_reflectance, original.probe_reflectance);
  EXPECT_EQ(loaded.post_radius_m, original.post_radius_m);
  EXPECT_EQ(loaded.post_albedo, original.post_albedo);
}

TEST(RigFile, RejectsEachMalformedCaseWithOneLineNamingFileAndField) {
  TempFolder folder;
  auto load = [](const std::string& path) { return [path] { config::loadRigFile(path); }; };
  auto rigWith = [&](const std::string& name, const std::string& from, const std::string& to) {
    std::string text = kGoodRig;
    if (!from.empty()) text.replace(text.find(from), from.size(), to);
    return folder.write(name, text);
  };
  std::string family = rigWith("family.yaml", "tag36h11", "tag36h12");
  expectConfigError(load(family), family, "tag_family", "not one of");
  std::string id = rigWith("id.yaml", "tag_id: 7", "tag_id: 587");  // tag36h11 has ids 0..586
  expectConfigError(load(id), id, "tag_id", "out of range");
  std::string negative_id = rigWith("negative_id.yaml", "tag_id: 7", "tag_id: -1");
  expectConfigError(load(negative_id), negative_id, "tag_id", "out of range");
  std::string size = rigWith("size.yaml", "tag_size: 0.08", "tag_size: 0");
  expectConfigError(load(size), size, "tag_size", "in [0.001, 10]");
  // Implausible values that once passed and crashed or wrote inf later
  // (issue 15, D6, D7, D8, D20).
  std::string size_tiny = rigWith("size_tiny.yaml", "tag_size: 0.08", "tag_size: 1e-300");
  expectConfigError(load(size_tiny), size_tiny, "tag_size", "in [0.001, 10]");
  std::string size_huge = rigWith("size_huge.yaml", "tag_size: 0.08", "tag_size: 1e308");
  expectConfigError(load(size_huge), size_huge, "tag_size", "in [0.001, 10]");
  std::string centre_far = rigWith("centre_far.yaml", "[0.1, -0.02, 0.03]", "[1e308, -0.02, 0.03]");
  expectConfigError(load(centre_far), centre_far, "probe_center", "out of range");
  std::string centre_1e6 = rigWith("centre_1e6.yaml", "[0.1, -0.02, 0.03]", "[1e6, -0.02, 0.03]");
  expectConfigError(load(centre_1e6), centre_1e6, "probe_center", "out of range");
  std::string dim_ball = folder.write("dim_ball.yaml", std::string(kGoodRig) + "probe_reflectance: 1e-300\n");
  expectConfigError(load(dim_ball), dim_ball, "probe_reflectance", "[0.01, 1]");
  std::string dim_white = folder.write("dim_white.yaml", std::string(kGoodRig) + "tag_white_albedo: 1e-320\n");
  expectConfigError(load(dim_white), dim_white, "tag_white_albedo", "[0.01, 1]");
  std::string size_text = rigWith("size_text.yaml", "tag_size: 0.08", "tag_size: ten");
  expectConfigError(load(size_text), size_text, "tag_size", "expected a number");
  std::string size_inf = rigWith("size_inf.yaml", "tag_size: 0.08", "tag_size: .inf");
  expectConfigError(load(size_inf), size_inf, "tag_size", "finite");
  // OpenCV keeps a comment after an unquoted text value as part of the text.
  std::string trailing_comment = rigWith("trailing_comment.yaml", "tag_family: tag36h11", "tag_family: tag36h11  # printed");
  expectConfigError(load(trailing_comment), trailing_comment, "tag_family", "end-of-line comments");
  std::string center_short = rigWith("center_short.yaml", "[0.1, -0.02, 0.03]", "[0.1, -0.02]");
  expectConfigError(load(center_short), center_short, "probe_center", "expected 3 numbers");
  std::string center_nan = rigWith("center_nan.yaml", "[0.1, -0.02, 0.03]", "[0.1, .nan, 0.03]");
  expectConfigError(load(center_nan), center_nan, "probe_center[1]", "finite");
  std::string radius_missing = rigWith("radius_missing.yaml", "probe_radius: 0.03\n", "");
  expectConfigError(load(radius_missing), radius_missing, "probe_radius", "missing");
  std::string reflectance = folder.write("reflectance.yaml", std::string(kGoodRig) + "probe_reflectance: 0\n");
  expectConfigError(load(reflectance), reflectance, "probe_reflectance", "[0.01, 1]");
  std::string typo = folder.write("typo.yaml", std::string(kGoodRig) + "probe_reflectence: 0.7\n");
  expectConfigError(load(typo), typo, "probe_reflectence", "unknown field");
  // A post no thinner than the ball, or under a ball that rests on the
  // ground (kGoodRig's centre is at z = probe_radius), or of an albedo past 1.
  auto raisedWith = [&](const std::string& name, const std::string& extra) {
    std::string text = kGoodRig;
    text.replace(text.find("[0.1, -0.02, 0.03]"), 18, "[0.1, -0.02, 0.08]");
    return folder.write(name, text + extra);
  };
  const std::string raised = raisedWith("raised.yaml", "");
  std::string thick = raisedWith("thick.yaml", "post_radius: 0.03\n");
  expectConfigError(load(thick), thick, "post_radius", "[0, probe_radius)");
  std::string grounded = folder.write("grounded.yaml", std::string(kGoodRig) + "post_radius: 0.003\n");
  expectConfigError(load(grounded), grounded, "post_radius", "on the ground");
  std::string bright = folder.write("bright.yaml", std::string(kGoodRig) + "post_albedo: 1.5\n");
  expectConfigError(load(bright), bright, "post_albedo", "out of range");
  std::string dim_post = folder.write("dim_post.yaml", std::string(kGoodRig) + "post_albedo: 1e-320\n");
  expectConfigError(load(dim_post), dim_post, "post_albedo", "0 (unknown) or in [0.01, 1]");
  EXPECT_EQ(config::loadRigFile(raised).post_radius_m, 0.0) << "no post unless one is described";
  std::string twice = folder.write("twice.yaml", std::string(kGoodRig) + "tag_id: 8\n");
  expectConfigError(load(twice), twice, "tag_id", "more than once");
  std::string not_a_map = folder.write("not_a_map.yaml", "- 1\n- 2\n");
  expectConfigError(load(not_a_map), not_a_map, "");
}

TEST(RigFile, SavingAnInvalidRigFailsBeforeWriting) {
  TempFolder folder;
  RigGeometry rig;
  rig.probe_radius_m = -1.0;
  std::string path = folder.file("rig.yaml");
  expectConfigError([&] { config::saveRigFile(path, rig); }, path, "probe_radius");
  EXPECT_FALSE(std::filesystem::exists(path));
}

// The published sizes of the classic families (AprilTag's documentation:
// tag36h11 has 587 codes, tag25h9 35, tag16h5 30), and the name each
// family reports for itself, so a table entry wired to the wrong
// constructor is caught.
TEST(RigFile, TagFamiliesHaveTheirPublishedSizesAndNames) {
  const std::pair<const char*, int> published[] = {{"tag36h11", 587}, {"tag25h9", 35}, {"tag16h5", 30}};
  for (const auto& [family, code_count] : published) {
    const char* name = family;  // clang 14 cannot capture a structured binding
    auto known = std::find_if(config::knownTagFamilies().begin(), config::knownTagFamilies().end(),
                              [&](const config::TagFamilyInfo& info) { return info.name == name; });
    ASSERT_NE(known, config::knownTagFamilies().end()) << name;
    EXPECT_EQ(known->code_count, code_count) << name;
  }
  EXPECT_EQ(config::knownTagFamilies().size(), aprilTagFamilies().size());
  for (const AprilTagFamilyFactory& factory : aprilTagFamilies()) {
    const AprilTagFamilyHandle family = createAprilTagFamily(factory.name);
    ASSERT_TRUE(family) << factory.name;
    EXPECT_STREQ(family->name, factory.name);
  }
}

TEST(ConfigReader, ReadsNestedSectionsBooleansAndChoices) {
  ConfigReader file = ConfigReader::fromText(
      "title: kiosk\nverbose: yes\nsim:\n  env: studio\n  frames: 120\n  jitter_px: 0.5\n  enabled: false\n", "app.yaml");
  EXPECT_EQ(file.readString("title"), "kiosk");
  EXPECT_TRUE(file.readBool("verbose", false));
  ConfigReader sim = file.section("sim");
  EXPECT_EQ(sim.readString("env", "parking", {"studio", "parking"}), "studio");
  EXPECT_EQ(sim.readInt("frames", 10, config::Range::atLeast(1)), 120);
  EXPECT_DOUBLE_EQ(sim.readDouble("jitter_px", 0.0, {0.0, 2.0}), 0.5);
  EXPECT_FALSE(sim.readBool("enabled", true));
  EXPECT_EQ(sim.readDouble("absent_with_default", 3.25), 3.25);
  sim.rejectUnknownFields();
  file.rejectUnknownFields();

  // An absent section reads as empty: defaults apply, required fields are
  // reported with their dotted name.
  ConfigReader display = file.section("display");
  EXPECT_EQ(display.readInt("width", 800), 800);
  expectConfigError([&] { display.readString("mode"); }, "app.yaml", "display.mode", "missing");
}

TEST(ConfigReader, ReportsSectionErrorsWithDottedNames) {
  ConfigReader file = ConfigReader::fromText("sim:\n  env: studoi\n  envv: x\nlights: 3\n", "app.yaml");
  ConfigReader sim = file.section("sim");
  expectConfigError([&] { sim.readString("env", "studio", {"studio", "parking"}); }, "app.yaml", "sim.env", "studoi");
  expectConfigError([&] { sim.rejectUnknownFields(); }, "app.yaml", "sim.envv", "unknown field");
  expectConfigError([&] { file.section("lights"); }, "app.yaml", "lights", "expected a section");
  expectConfigError([&] { file.readBool("lights"); }, "app.yaml", "lights", "true or false");
  ConfigReader values = ConfigReader::fromText("ratio: 1.5\ncount: 2.5\n", "values.yaml");
  expectConfigError([&] { values.readDouble("ratio", 0.0, config::Range::openClosed(0.0, 1.0)); }, "values.yaml", "ratio",
                    "in (0, 1]");
  expectConfigError([&] { values.readInt("count"); }, "values.yaml", "count", "expected an integer");
}

}  // namespace
}  // namespace probelight

namespace probelight {
namespace {

// OpenCV's YAML parser recursed without a limit: 50,000 nested brackets
// crashed every loader with SIGSEGV (issue 15, D1). Now one line naming the
// file and the line, for flow nesting and for block indentation, before
// OpenCV sees the text; brackets in comments and quoted text do not count.
TEST(ConfigReader, TooDeepNestingOrATooLargeFileIsOneLineNotACrash) {
  TempFolder folder;
  const std::string deep = folder.write("deep.yaml", "x: " + std::string(50000, '[') + std::string(50000, ']') + "\n");
  expectConfigError([&] { config::loadRigFile(deep); }, deep, "", "nested deeper than 64 levels at line 1");
  expectConfigError([&] { config::loadCameraFile(deep); }, deep, "", "nested deeper than 64 levels");
  std::string block = "a:\n";
  for (int i = 1; i < 1100; ++i) block += std::string(static_cast<std::size_t>(i), ' ') + "b" + std::to_string(i) + ":\n";
  const std::string indented = folder.write("indented.yaml", block);
  expectConfigError([&] { config::loadRigFile(indented); }, indented, "", "indented past column 1024");
  // A file of a few MB of spaces is no settings file (and is not parsed).
  const std::string large = folder.write("large.yaml", "a: 1\n" + std::string(config::kMaxConfigFileBytes, '\n'));
  expectConfigError([&] { config::loadRigFile(large); }, large, "", "larger than 16 MiB");
  // At the limit, and with brackets in a comment and a quoted string, it parses.
  const std::string nested_ok = std::string(64, '[') + "1" + std::string(64, ']');
  ConfigReader ok = ConfigReader::fromText("a: " + nested_ok + "\n# " + std::string(100, '[') +
                                               "\nb: \"" + std::string(100, '{') + "\"\n",
                                           "ok.yaml");
  EXPECT_EQ(ok.readString("b", ""), std::string(100, '{'));
  expectConfigError([] { ConfigReader::fromText("a: " + std::string(65, '[') + std::string(65, ']') + "\n", "deep65.yaml"); },
                    "deep65.yaml", "", "nested deeper than 64");
}

// OpenCV 4.6's reader steps 3 characters past wherever its top level ends
// and loops forever when it lands on a '-' (libFuzzer found three such
// files, two of them in CI as 10 s timeouts), and it reads only the first
// of several documents without a word. Each shape that can end the top
// level early is now one line naming the file and the line; a leading
// "---", a closing "..." and comments after either still read.
TEST(ConfigReader, ASecondDocumentOrTextAfterTheEndIsOneLineNotAHang) {
  TempFolder folder;
  const auto expectRefused = [&](const std::string& name, const std::string& text, const std::string& problem) {
    const std::string path = folder.write(name, text);
    expectConfigError([&] { config::loadRigFile(path); }, path, "", problem);
  };
  expectRefused("hang.yaml", "%YAML:1.0\ntag_id: 7\n...\n-\n",
                "line 4: more after the end of the document ('...' at line 3)");
  // OpenCV takes "..." and "---" as markers whatever follows them on the
  // line; each of these, then a shorter line, looped forever.
  expectRefused("glued.yaml", "tag_id: 7\n...-b\n\n", "line 2: text after '...' on its line");
  expectRefused("spaced.yaml", "tag_id: 7\n... - b\n\n", "line 2: text after '...' on its line");
  expectRefused("dashes.yaml", "----m\n\nm\n\n", "line 1: text after '---' on its line");
  expectRefused("inline.yaml", "--- -m\n\nm\n\n", "line 1: text after '---' on its line");
  // An indented top level ends at the first line less indented, the same
  // early end.
  expectRefused("indented.yaml", " tag_id: 7\ntag_family: tag36h11\n\n", "line 1: the top level is indented");
  expectRefused("second.yaml", "---\ntag_id: 7\n---\ntag_id: 8\n", "line 3: a second YAML document begins");
  expectRefused("after_end.yaml", "tag_id: 7\n...\r\n---\ntag_id: 8\n", "line 3: more after the end");
  ConfigReader ok = ConfigReader::fromText("%YAML:1.0\n--- # settings\n# a comment\na: 1\nb: '...'\n...\n\n  # done\n", "ok.yaml");
  EXPECT_EQ(ok.readInt("a"), 1);
  EXPECT_EQ(ok.readString("b", ""), "...");
  ConfigReader marker_then_comment = ConfigReader::fromText("---# settings\na:\n  b: 2\n...# done\n", "tight.yaml");
  EXPECT_EQ(marker_then_comment.section("a").readInt("b"), 2);
}

// OpenCV read these silently as other numbers (issue 15, D2, D3): now each
// is one line naming the file, the line and the literal.
TEST(ConfigReader, IntegersThatOpenCvWouldWrapOrReadAsOctalAreRefused) {
  TempFolder folder;
  const std::string good = "tag_family: tag36h11\ntag_id: 7\ntag_size: 0.08\nprobe_center: [0.1, -0.02, 0.03]\nprobe_radius: 0.03\n";
  auto rigWithId = [&](const std::string& name, const std::string& id) {
    std::string text = good;
    text.replace(text.find("tag_id: 7"), 9, "tag_id: " + id);
    return folder.write(name, text);
  };
  const std::string wraps = rigWithId("wraps.yaml", "4294967297");  // was read as 1
  expectConfigError([&] { config::loadRigFile(wraps); }, wraps, "", "line 2: 4294967297 does not fit in a 32-bit integer");
  const std::string huge = rigWithId("huge.yaml", "99999999999999999999");  // was read as -1
  expectConfigError([&] { config::loadRigFile(huge); }, huge, "", "does not fit in a 32-bit integer");
  const std::string octal = rigWithId("octal.yaml", "010");  // was read as 8
  expectConfigError([&] { config::loadRigFile(octal); }, octal, "", "010 has a leading zero");
  const std::string hex = rigWithId("hex.yaml", "0x10");
  expectConfigError([&] { config::loadRigFile(hex); }, hex, "", "0x10 is hexadecimal");
  std::string size_text = good;
  size_text.replace(size_text.find("tag_size: 0.08"), 14, "tag_size: 010");  // was 8 m
  const std::string octal_size = folder.write("octal_size.yaml", size_text);
  expectConfigError([&] { config::loadRigFile(octal_size); }, octal_size, "", "leading zero");
  // What stays readable: the largest int, a negative one, decimals with
  // leading zeros, keys with digits, times inside quotes.
  ConfigReader ok = ConfigReader::fromText(
      "a: 2147483647\nb: -5\nc: 0.08\nd0: 0\ne: \"14:05:09\"\nf: [0., 0.5, 1e-3]\n", "ok.yaml");
  EXPECT_EQ(ok.readInt("a"), 2147483647);
  EXPECT_EQ(ok.readInt("b", 0, config::Range::closed(-10, 10)), -5);
  EXPECT_DOUBLE_EQ(ok.readDouble("c"), 0.08);
  EXPECT_EQ(ok.readInt("d0"), 0);
}

}  // namespace
}  // namespace probelight
