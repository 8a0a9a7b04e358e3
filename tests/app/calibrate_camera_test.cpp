// `probelight calibrate-camera`: runs the real binary on OpenCV's 13 sample
// chessboard views (tests/data/chessboard) and checks the result against
// OpenCV's own calibration of them (left_intrinsics.yml), then the rejections
// and the failure paths (exit 2 with one line).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/calibrate_camera.hpp"
#include "config/camera_file.hpp"

namespace probelight {
namespace {

namespace fs = std::filesystem;

const fs::path kChessboardDir = fs::path(PROBELIGHT_TEST_DATA_DIR) / "chessboard";

struct CalibrateCameraResult {
  int exit_status = -1;
  std::string stdout_text, stderr_text;
};

std::string readText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

int lineCount(const std::string& text) { return static_cast<int>(std::count(text.begin(), text.end(), '\n')); }

// OpenCV's calibration of the same views (calibration.cpp sample, run with
// CALIB_FIX_ASPECT_RATIO, hence fx == fy there).
struct Reference {
  double fx, fy, cx, cy, rms;
};
Reference readReference() {
  cv::FileStorage fs((kChessboardDir / "left_intrinsics.yml").string(), cv::FileStorage::READ);
  EXPECT_TRUE(fs.isOpened());
  cv::Mat k;
  fs["camera_matrix"] >> k;
  double rms = 0;
  fs["avg_reprojection_error"] >> rms;
  return {k.at<double>(0, 0), k.at<double>(1, 1), k.at<double>(0, 2), k.at<double>(1, 2), rms};
}

std::vector<fs::path> sampleViews() {
  std::vector<fs::path> views;
  for (const auto& entry : fs::directory_iterator(kChessboardDir))
    if (entry.path().extension() == ".jpg") views.push_back(entry.path());
  std::sort(views.begin(), views.end());
  return views;
}

// Tolerances. The reference comes from OpenCV's calibration sample: fx tied
// to fy and cornerSubPix with a fixed 11 px half-window. On left02, whose
// squares are 22 px, that 23 px window reaches the neighbouring corners: the
// reference fits that view at 1.18 px (the others at 0.16-0.38) and it pulls
// the result. Ours (window from each view's corner spacing) fits every view
// at 0.15-0.24 px and gives fx 533.3 (0.49% below), cx 342.1 (0.15 px), cy
// 234.0 (1.5 px below); the sample's own settings without left02 give fx
// 534.1, cy 233.7. So the gap is mostly the reference's error, with ours
// +-0.6-0.7 px (1 sigma, OpenCV's estimate, printed by the command). 1% of fx
// (5.4 px) and 2 px for the principal point hold that, and catch a fixed
// principal point (cx 319.5, 23 px off) or a fit without distortion (fx +4%).
constexpr double kFocalRelTolerance = 0.01;
constexpr double kPrincipalTolerancePx = 2.0;
// Corners refined to sub-pixel on sharp 640x480 views fit to a few tenths of
// a pixel (OpenCV's own fit: 0.39 px). 1 px is what a misdetected corner or
// a model without distortion (1.56 px here) exceed.
constexpr double kMaxRmsPx = 1.0;
// Tighter, for these views only: measured 0.181 px. Skipping cornerSubPix
// gives 0.38 px with fx still inside the 1% above (531.2); 0.3 px catches it.
// (The sample's fixed 11 px window gives 0.41 px, but then the outlier rule
// drops left02 and the refit reaches 0.23 px, which passes, as it should.)
constexpr double kSampleRmsPx = 0.3;

class CalibrateCamera : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::temp_directory_path() / ("probelight_calibrate_" + std::to_string(getpid()) + "_" + name);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (std::getenv("PROBELIGHT_KEEP_TEST_DIRS")) {
      std::cout << "[ kept     ] " << dir_.string() << "\n";
      return;
    }
    if (!HasFailure()) fs::remove_all(dir_);
  }

  CalibrateCameraResult run(const std::string& args) const {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string command =
        std::string(PROBELIGHT_BINARY) + " calibrate-camera " + args + " >" + out.string() + " 2>" + err.string();
    const int status = std::system(command.c_str());
    CalibrateCameraResult result;
    result.exit_status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.stdout_text = readText(out);
    result.stderr_text = readText(err);
    return result;
  }

  // Calibrates the views matched by `glob`, checks exit 0 and the result
  // against the reference; returns the command's output.
  CalibrateCameraResult calibrateAndCompare(const std::string& glob) {
    const fs::path yaml = dir_ / "camera.yaml";
    CalibrateCameraResult result = run("--images '" + glob + "' --board 9x6 --square 0.025 --out " + yaml.string());
    EXPECT_EQ(result.exit_status, 0) << result.stderr_text;
    std::cout << result.stdout_text;

    const Reference ref = readReference();
    const CameraIntrinsics camera = config::loadCameraFile(yaml.string());  // throws if it does not load back
    EXPECT_EQ(camera.width_px, 640);
    EXPECT_EQ(camera.height_px, 480);
    EXPECT_NEAR(camera.fx_px, ref.fx, kFocalRelTolerance * ref.fx);
    EXPECT_NEAR(camera.fy_px, ref.fy, kFocalRelTolerance * ref.fy);
    EXPECT_NEAR(camera.cx_px, ref.cx, kPrincipalTolerancePx);
    EXPECT_NEAR(camera.cy_px, ref.cy, kPrincipalTolerancePx);

    std::smatch match;
    const std::regex rms_line("RMS reprojection error: ([0-9.]+) px");
    EXPECT_TRUE(std::regex_search(result.stdout_text, match, rms_line)) << result.stdout_text;
    if (!match.empty()) {
      const double rms = std::stod(match[1]);
      EXPECT_GT(rms, 0.0);
      EXPECT_LT(rms, kMaxRmsPx);
    }
    return result;
  }

  fs::path dir_;
};

TEST_F(CalibrateCamera, MatchesOpenCVsReferenceOnTheSampleViews) {
  const CalibrateCameraResult result = calibrateAndCompare((kChessboardDir / "left*.jpg").string());
  std::smatch match;
  ASSERT_TRUE(std::regex_search(result.stdout_text, match, std::regex("RMS reprojection error: ([0-9.]+) px")));
  EXPECT_LT(std::stod(match[1]), kSampleRmsPx);
  // Every view printed with its own error.
  for (const fs::path& view : sampleViews()) {
    if (result.stderr_text.find(view.string()) == std::string::npos) {
      EXPECT_NE(result.stdout_text.find(view.string()), std::string::npos) << view;
    }
  }
}

TEST_F(CalibrateCamera, RejectsBadFilesWithReasonsAndStillCalibrates) {
  const fs::path views = dir_ / "views";
  fs::create_directories(views);
  for (const fs::path& view : sampleViews()) fs::copy_file(view, views / view.filename());
  // A real photo without a chessboard (tags on a lawn), at the views' size.
  cv::Mat photo = cv::imread(
      (fs::path(PROBELIGHT_TEST_DATA_DIR) / "apriltag-photos" / "33369213973_9d9bb4cc96_c.jpg").string());
  ASSERT_FALSE(photo.empty());
  cv::resize(photo, photo, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
  ASSERT_TRUE(cv::imwrite((views / "no_board.png").string(), photo));
  // A file that claims to be a JPEG and is not.
  std::ofstream((views / "corrupt.jpg").string()) << "not a JPEG, just text in a .jpg";
  // A real view at half size: the board is found, but its size is wrong.
  cv::Mat small = cv::imread((kChessboardDir / "left01.jpg").string());
  cv::resize(small, small, cv::Size(320, 240), 0, 0, cv::INTER_AREA);
  ASSERT_TRUE(cv::imwrite((views / "small.png").string(), small));

  const CalibrateCameraResult result = calibrateAndCompare((views / "*").string());
  const std::string& err = result.stderr_text;
  EXPECT_NE(err.find("rejected " + (views / "no_board.png").string() + ": no 9x6 chessboard found"), std::string::npos)
      << err;
  EXPECT_NE(err.find("rejected " + (views / "corrupt.jpg").string() + ": not a PNG, JPEG, BMP or PNM image"), std::string::npos) << err;
  EXPECT_NE(err.find("rejected " + (views / "small.png").string() + ": size 320x240 differs from the first view's 640x480"),
            std::string::npos)
      << err;
  EXPECT_EQ(result.stdout_text.find("no_board.png"), std::string::npos);
  // A line per view as it was read, with its place: found on stdout, rejected on stderr.
  EXPECT_NE(err.find("] rejected " + (views / "no_board.png").string()), std::string::npos) << err;
  EXPECT_NE(result.stdout_text.find(": board found"), std::string::npos) << result.stdout_text;
  EXPECT_NE(result.stdout_text.find("fitting the camera to "), std::string::npos) << result.stdout_text;
}

TEST_F(CalibrateCamera, TooFewUsableViewsIsExit2WithOneLine) {
  const fs::path views = dir_ / "views";
  fs::create_directories(views);
  const auto all = sampleViews();
  for (int i = 0; i < kMinCalibrationViews - 1; ++i) fs::copy_file(all[i], views / all[i].filename());
  std::ofstream((views / "corrupt.jpg").string()) << "garbage";
  const CalibrateCameraResult result =
      run("--images '" + (views / "*").string() + "' --board 9x6 --square 0.025 --out " + (dir_ / "c.yaml").string());
  EXPECT_EQ(result.exit_status, 2);
  // The corrupt file's rejection, then the one line that says why it stopped.
  EXPECT_EQ(lineCount(result.stderr_text), 2) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("only " + std::to_string(kMinCalibrationViews - 1) + " usable views of " +
                                    std::to_string(kMinCalibrationViews) + " files"),
            std::string::npos)
      << result.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "c.yaml"));
}

TEST_F(CalibrateCamera, NoMatchingFileIsExit2) {
  const CalibrateCameraResult result = run("--images '" + (dir_ / "nothing_*.png").string() +
                                   "' --board 9x6 --square 0.025 --out " + (dir_ / "c.yaml").string());
  EXPECT_EQ(result.exit_status, 2);
  EXPECT_EQ(lineCount(result.stderr_text), 1) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("no file matches --images"), std::string::npos) << result.stderr_text;
}

TEST_F(CalibrateCamera, BadFlagsAreExit2NamingTheFlag) {
  const std::string glob = "'" + (kChessboardDir / "left*.jpg").string() + "'";
  const std::string out = (dir_ / "c.yaml").string();
  const struct {
    std::string args, flag;
  } cases[] = {
      {"--images " + glob + " --board 9by6 --square 0.025 --out " + out, "--board"},
      {"--images " + glob + " --board 1x1 --square 0.025 --out " + out, "--board"},
      {"--images " + glob + " --board 9x --square 0.025 --out " + out, "--board"},
      {"--images " + glob + " --board 9x6 --square 0 --out " + out, "--square"},
      {"--images " + glob + " --board 9x6 --square -0.025 --out " + out, "--square"},
      {"--images " + glob + " --board 9x6 --square 25 --out " + out, "--square"},
      {"--images " + glob + " --board 9x6 --square abc --out " + out, "--square"},
      {"--images " + glob + " --square 0.025 --out " + out, "--board"},
      {"--images " + glob + " --board 9x6 --square 0.025", "--out"},
      {"--board 9x6 --square 0.025 --out " + out, "--images"},
  };
  for (const auto& c : cases) {
    const CalibrateCameraResult result = run(c.args);
    EXPECT_EQ(result.exit_status, 2) << c.args;
    EXPECT_EQ(lineCount(result.stderr_text), 1) << c.args << "\n" << result.stderr_text;
    EXPECT_NE(result.stderr_text.find(c.flag), std::string::npos) << c.args << "\n" << result.stderr_text;
  }
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(CalibrateCamera, UnwritableOutIsExit2WithOneLine) {
  const CalibrateCameraResult result = run("--images '" + (kChessboardDir / "left*.jpg").string() +
                                   "' --board 9x6 --square 0.025 --out " + (dir_ / "missing" / "c.yaml").string());
  EXPECT_EQ(result.exit_status, 2);
  EXPECT_EQ(lineCount(result.stderr_text), 1) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("c.yaml"), std::string::npos) << result.stderr_text;
}

// The outlier rule on the per-view errors OpenCV's own calibration of these
// views reports (left_intrinsics.yml: its left02 at 1.18 px, from a corner
// window wider than that view's 22 px squares), and on a uniformly noisier set.
TEST(CalibrationOutliers, DropsAViewFarAboveTheMedianButNotAUniformlyNoisySet) {
  cv::FileStorage fs((kChessboardDir / "left_intrinsics.yml").string(), cv::FileStorage::READ);
  cv::Mat per_view;
  fs["per_view_reprojection_errors"] >> per_view;
  ASSERT_EQ(per_view.total(), 13u);
  std::vector<double> errors(per_view.begin<float>(), per_view.end<float>());
  const double limit = outlierLimitPx(errors);
  EXPECT_NEAR(limit, kOutlierFloorPx, 1e-12);  // 3 x the 0.20 px median is below the floor
  EXPECT_EQ(std::count_if(errors.begin(), errors.end(), [&](double e) { return e > limit; }), 1);
  EXPECT_GT(errors[1], limit);  // left02
  // A blurrier camera: every view near 0.8 px, one at 1.5 px, is not an
  // outlier (3 x 0.8 = 2.4 px): the rule looks for a view unlike the others.
  std::vector<double> noisy(12, 0.8);
  noisy.push_back(1.5);
  EXPECT_NEAR(outlierLimitPx(noisy), 2.4, 1e-12);
  // Where the median is well above the floor, the factor decides.
  noisy.push_back(2.5);
  EXPECT_GT(2.5, outlierLimitPx(noisy));
}

}  // namespace
}  // namespace probelight
