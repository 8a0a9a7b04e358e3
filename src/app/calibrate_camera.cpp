#include "app/calibrate_camera.hpp"

#include <glob.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <sstream>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "capture/rgb_image_io.hpp"
#include "config/camera_file.hpp"
#include "config/config_reader.hpp"
#include "core/types.hpp"

namespace probelight {

namespace {

namespace fs = std::filesystem;

struct View {
  std::string path;
  std::vector<cv::Point2f> corners;
  double rms_px = 0.0;
};

// Sorted, so the "first view" (the size reference) and the printed order do
// not depend on the file system's order. Folders are skipped; every other
// match is tried, so a stray file is reported rather than silently ignored.
std::vector<std::string> globFiles(const std::string& pattern) {
  std::vector<std::string> files;
  glob_t matches{};
  if (::glob(pattern.c_str(), 0, nullptr, &matches) == 0) {
    for (std::size_t i = 0; i < matches.gl_pathc; ++i) {
      std::error_code ignored;
      if (!fs::is_directory(matches.gl_pathv[i], ignored)) files.emplace_back(matches.gl_pathv[i]);
    }
  }
  ::globfree(&matches);
  std::sort(files.begin(), files.end());
  return files;
}

std::string fixed(double value, int decimals) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(decimals) << value;
  return text.str();
}

std::string sizeText(const cv::Size& size) { return std::to_string(size.width) + "x" + std::to_string(size.height); }

// cornerSubPix's half window must stay inside the two squares that meet at a
// corner: a window reaching the next corner sees its edges too and pulls the
// estimate toward it. OpenCV's sample uses 11 (a 23 px window), fine for
// squares of 30+ px but too wide for a board far away, so the window follows
// the smallest corner spacing found in this view: 40% of it, 2 to 11 px.
int subPixHalfWindow(const std::vector<cv::Point2f>& corners, const cv::Size& board) {
  double spacing = 1e9;
  for (int r = 0; r < board.height; ++r)
    for (int c = 0; c < board.width; ++c) {
      const cv::Point2f& p = corners[r * board.width + c];
      if (c + 1 < board.width) spacing = std::min(spacing, cv::norm(p - corners[r * board.width + c + 1]));
      if (r + 1 < board.height) spacing = std::min(spacing, cv::norm(p - corners[(r + 1) * board.width + c]));
    }
  return std::clamp(static_cast<int>(std::floor(0.4 * spacing)), 2, 11);
}

struct Fit {
  cv::Mat camera_matrix, distortion;
  cv::Mat std_intrinsics;  // standard deviations: fx fy cx cy k1 k2 p1 p2 k3 ...
  double rms_px = 0.0;
};

// calibrateCamera with its default model: k1 k2 p1 p2 k3 (the 5 terms
// camera.yaml holds), fx and fy free, no fixed principal point.
Fit calibrate(std::vector<View>& views, const std::vector<cv::Point3f>& board_points, const cv::Size& image_size) {
  std::vector<std::vector<cv::Point3f>> object_points(views.size(), board_points);
  std::vector<std::vector<cv::Point2f>> image_points;
  for (const View& view : views) image_points.push_back(view.corners);
  Fit fit;
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat std_extrinsics, per_view;
  fit.rms_px = cv::calibrateCamera(object_points, image_points, image_size, fit.camera_matrix, fit.distortion, rvecs,
                                   tvecs, fit.std_intrinsics, std_extrinsics, per_view, 0,
                                   cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));
  for (std::size_t i = 0; i < views.size(); ++i) views[i].rms_px = per_view.at<double>(static_cast<int>(i));
  return fit;
}

}  // namespace

double outlierLimitPx(std::vector<double> view_rms_px) {
  // The upper median for an even count: the limit only needs a typical view.
  std::nth_element(view_rms_px.begin(), view_rms_px.begin() + view_rms_px.size() / 2, view_rms_px.end());
  return std::max(kOutlierMedianFactor * view_rms_px[view_rms_px.size() / 2], kOutlierFloorPx);
}

int runCalibrateCamera(const CalibrateCameraOptions& options, std::ostream& out, std::ostream& log) {
  // OpenCV logs its own line when FileStorage cannot open --out; ours names
  // the file already, and a bad file must stay one line.
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  const std::string prefix = "probelight: calibrate-camera: ";
  const cv::Size board(options.board_cols, options.board_rows);
  const std::vector<std::string> files = globFiles(options.images);
  if (files.empty()) {
    log << prefix << "no file matches --images '" << options.images << "'\n";
    return 2;
  }

  // The board in its own plane (z = 0), row-major like findChessboardCorners'
  // output, in metres so the saved poses would be too.
  std::vector<cv::Point3f> board_points;
  for (int r = 0; r < board.height; ++r)
    for (int c = 0; c < board.width; ++c)
      board_points.emplace_back(static_cast<float>(c * options.square_m), static_cast<float>(r * options.square_m), 0.f);

  std::vector<View> views;
  cv::Size image_size;
  // A line per view as it is read (the board's search takes a while on a
  // big set): found on stdout, rejected on stderr, each with its place.
  std::string place;
  auto reject = [&](const std::string& path, const std::string& reason) {
    log << prefix << place << "rejected " << path << ": " << reason << "\n";
  };
  for (const std::string& path : files) {
    place = "[" + std::to_string(&path - files.data() + 1) + "/" + std::to_string(files.size()) + "] ";
    // Grey is what the detector and cornerSubPix work on; colour adds nothing.
    std::string why;
    const cv::Mat grey = readImageFile(path, cv::IMREAD_GRAYSCALE, &why);
    if (grey.empty()) {
      reject(path, why);
      continue;
    }
    if (image_size.empty()) image_size = grey.size();
    if (grey.size() != image_size) {
      reject(path, "size " + sizeText(grey.size()) + " differs from the first view's " + sizeText(image_size));
      continue;
    }
    // ADAPTIVE_THRESH + NORMALIZE_IMAGE: OpenCV's defaults, for uneven light.
    // FAST_CHECK: a quick look for any chessboard-like corners first, so
    // views without a board are rejected in milliseconds instead of after the
    // full search.
    std::vector<cv::Point2f> corners;
    const bool found = cv::findChessboardCorners(
        grey, board, corners, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK);
    if (!found) {
      reject(path, "no " + std::to_string(board.width) + "x" + std::to_string(board.height) +
                       " chessboard found (all inner corners must be in view)");
      continue;
    }
    const int half = subPixHalfWindow(corners, board);
    cv::cornerSubPix(grey, corners, cv::Size(half, half), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 40, 0.001));
    out << place << path << ": board found\n" << std::flush;
    views.push_back({path, std::move(corners), 0.0});
  }
  place.clear();

  const auto too_few = [&](const std::string& what) {
    log << prefix << "only " << views.size() << " usable view" << (views.size() == 1 ? "" : "s") << " of "
        << files.size() << " file" << (files.size() == 1 ? "" : "s") << what << " (at least " << kMinCalibrationViews
        << " needed)\n";
    return 2;
  };
  if (static_cast<int>(views.size()) < kMinCalibrationViews) return too_few("");

  Fit fit;
  try {
    out << "fitting the camera to " << views.size() << " views\n" << std::flush;
    fit = calibrate(views, board_points, image_size);
    // A view far worse than the rest (corners found on the wrong squares,
    // motion blur, a bent board) pulls the whole fit. Drop views above both
    // kOutlierMedianFactor x the median and kOutlierFloorPx, once, and refit.
    // The floor keeps a good set whole: at a 0.2 px median a 0.7 px view is
    // still a good view. Once only: refitting until nothing stands out would
    // eat into any set, since a refit always makes some view the worst.
    std::vector<double> errors;
    for (const View& view : views) errors.push_back(view.rms_px);
    const double limit = outlierLimitPx(errors);
    std::vector<View> kept;
    for (const View& view : views)
      if (view.rms_px <= limit) kept.push_back(view);
    if (kept.size() < views.size()) {
      if (static_cast<int>(kept.size()) < kMinCalibrationViews) {
        log << prefix << "warning: keeping " << views.size() - kept.size()
            << " outlier view(s) above " << fixed(limit, 2) << " px: dropping them would leave fewer than "
            << kMinCalibrationViews << "\n";
      } else {
        for (const View& view : views)
          if (view.rms_px > limit)
            reject(view.path, "reprojection error " + fixed(view.rms_px, 2) + " px is above " + fixed(limit, 2) +
                                  " px (the larger of " + fixed(kOutlierMedianFactor, 0) +
                                  "x the median view's and " + fixed(kOutlierFloorPx, 1) + " px)");
        views = std::move(kept);
        fit = calibrate(views, board_points, image_size);
      }
    }
  } catch (const cv::Exception& error) {
    log << prefix << "OpenCV's calibration failed: " << error.msg << "\n";
    return 1;
  }

  CameraIntrinsics camera;
  camera.width_px = image_size.width;
  camera.height_px = image_size.height;
  camera.fx_px = fit.camera_matrix.at<double>(0, 0);
  camera.fy_px = fit.camera_matrix.at<double>(1, 1);
  camera.cx_px = fit.camera_matrix.at<double>(0, 2);
  camera.cy_px = fit.camera_matrix.at<double>(1, 2);
  for (int i = 0; i < 5; ++i) camera.distortion[i] = fit.distortion.at<double>(i);
  try {
    config::saveCameraFile(options.out_path, camera);
  } catch (const config::ConfigError& error) {
    log << "probelight: " << error.what() << "\n";
    return 2;
  }

  out << "calibrate-camera: " << views.size() << " of " << files.size() << " files used, " << sizeText(image_size)
      << ", board " << board.width << "x" << board.height << " inner corners\n";
  out << "per-view RMS reprojection error (px):\n";
  for (const View& view : views) out << "  " << fixed(view.rms_px, 3) << "  " << view.path << "\n";
  out << "RMS reprojection error: " << fixed(fit.rms_px, 3) << " px over " << views.size() * board_points.size()
      << " corners\n";
  // With OpenCV's standard deviations (from the fit's Jacobian and residual),
  // so a person can tell a well-pinned focal length from a loose one.
  const auto sd = [&](int i) { return " +- " + fixed(fit.std_intrinsics.at<double>(i), 2); };
  out << "fx " << fixed(camera.fx_px, 2) << sd(0) << "  fy " << fixed(camera.fy_px, 2) << sd(1) << "  cx "
      << fixed(camera.cx_px, 2) << sd(2) << "  cy " << fixed(camera.cy_px, 2) << sd(3) << " px\n";
  out << "distortion k1 k2 p1 p2 k3: ";
  for (int i = 0; i < 5; ++i) out << (i ? " " : "") << std::setprecision(5) << camera.distortion[i];
  out << "\nwrote " << options.out_path << "\n";
  return 0;
}

}  // namespace probelight
