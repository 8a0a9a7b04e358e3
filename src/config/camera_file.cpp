#include "config/camera_file.hpp"

#include <optional>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace probelight::config {

namespace {

void checkFinite(const std::string& path, const char* field, double value) {
  if (!std::isfinite(value))
    throw ConfigError(path + ": field '" + field + "': must be finite, got " + formatNumber(value));
}

}  // namespace

void validateCameraIntrinsics(const CameraIntrinsics& camera, const std::string& path) {
  auto fail = [&](const char* field, const std::string& problem) {
    throw ConfigError(path + ": field '" + field + "': " + problem);
  };
  // Sizes: a frame the GPU can hold as one texture on the boards (8192 on
  // the Pi 5's V3D, 4096 on the Pi 4's for now); more is a typo, and would
  // allocate gigabytes in the simulator before anything else failed.
  if (camera.width_px <= 0 || camera.width_px > kMaxImageSidePx)
    fail("image_width", std::to_string(camera.width_px) + " is out of range, must be in [1, " +
                            std::to_string(kMaxImageSidePx) + "]");
  if (camera.height_px <= 0 || camera.height_px > kMaxImageSidePx)
    fail("image_height", std::to_string(camera.height_px) + " is out of range, must be in [1, " +
                             std::to_string(kMaxImageSidePx) + "]");
  for (double value : {camera.fx_px, camera.fy_px, camera.cx_px, camera.cy_px}) checkFinite(path, "camera_matrix", value);
  for (double value : camera.distortion) checkFinite(path, "distortion_coefficients", value);
  // Focal lengths a pinhole model can mean: 0.1x the larger side is a 157 deg
  // field of view (past what the pinhole model fits), 50x is 1.1 deg.
  const double side_px = std::max(camera.width_px, camera.height_px);
  for (double focal : {camera.fx_px, camera.fy_px})
    if (!(focal >= kMinFocalPerSide * side_px && focal <= kMaxFocalPerSide * side_px))
      fail("camera_matrix", "focal lengths fx=" + formatNumber(camera.fx_px) + ", fy=" + formatNumber(camera.fy_px) +
                                " are out of range, must be in [" + formatNumber(kMinFocalPerSide * side_px) + ", " +
                                formatNumber(kMaxFocalPerSide * side_px) + "] px for a " +
                                std::to_string(camera.width_px) + "x" + std::to_string(camera.height_px) + " image");
  // Wider than any calibration of a real lens gives (|k1|, |k2| stay below
  // a few, k3 below a few tens, p1 and p2 below 0.01), and small enough that
  // r^6 k3 cannot overflow anywhere in the image.
  const char* const names[5] = {"k1", "k2", "p1", "p2", "k3"};
  for (std::size_t i = 0; i < 5; ++i)
    if (!(std::abs(camera.distortion[i]) <= kMaxDistortion[i]))
      fail("distortion_coefficients", std::string(names[i]) + " = " + formatNumber(camera.distortion[i]) +
                                          " is out of range, must be within +-" + formatNumber(kMaxDistortion[i]));
  // The principal point is near the image centre for any real lens; outside
  // the image means a wrong resolution or a matrix from another camera.
  if (camera.cx_px < 0 || camera.cx_px > camera.width_px || camera.cy_px < 0 || camera.cy_px > camera.height_px)
    fail("camera_matrix", "principal point (" + formatNumber(camera.cx_px) + ", " + formatNumber(camera.cy_px) +
                              ") is outside the " + std::to_string(camera.width_px) + "x" +
                              std::to_string(camera.height_px) + " image");
  // 0 is focus at infinity; negative is past infinity, no lens goes there.
  if (camera.lens_position_dioptres &&
      !(*camera.lens_position_dioptres >= 0.0 && *camera.lens_position_dioptres <= kMaxLensPositionDioptres))
    fail("lens_position_dioptres", formatNumber(*camera.lens_position_dioptres) + " is out of range, must be in [0, " +
                                       formatNumber(kMaxLensPositionDioptres) +
                                       "] (dioptres: 1 / the focus distance in metres)");
  if (const std::optional<double> fold = radialFoldInsideImage(camera))
    fail("distortion_coefficients",
         "k1, k2, k3 fold the image: the distorted radius stops growing at " + formatNumber(*fold) +
             " (normalised), inside the frame, so two directions land on one pixel and undistorting is ambiguous");
}

std::optional<double> radialFoldInsideImage(const CameraIntrinsics& camera) {
  const double k1 = camera.distortion[0], k2 = camera.distortion[1], k3 = camera.distortion[4];
  // The frame's farthest corner, as a distorted normalised radius.
  double corner_radius = 0.0;
  for (double x : {-0.5 - camera.cx_px, camera.width_px - 0.5 - camera.cx_px})
    for (double y : {-0.5 - camera.cy_px, camera.height_px - 0.5 - camera.cy_px})
      corner_radius = std::max(corner_radius, std::hypot(x / camera.fx_px, y / camera.fy_px));
  // rd(r) = r (1 + k1 r^2 + k2 r^4 + k3 r^6) must rise until it reaches the
  // corner's radius. Walked in steps of 1/4096 of that radius: a fold
  // narrower than a step is narrower than a pixel everywhere probelight
  // looks (the frame is at most 8192 px on a side).
  const double step = corner_radius / 4096.0;
  for (double r = 0.0; r <= 64.0 * corner_radius; r += step) {
    const double r2 = r * r;
    const double rd = r * (1.0 + r2 * (k1 + r2 * (k2 + r2 * k3)));
    if (rd >= corner_radius) return std::nullopt;
    const double slope = 1.0 + r2 * (3.0 * k1 + r2 * (5.0 * k2 + r2 * 7.0 * k3));
    if (slope <= 0.0) return r;
  }
  return std::nullopt;  // grows too slowly to reach the corner within 64x: no fold, only a very flat lens
}

CameraIntrinsics loadCameraFile(const std::string& path) {
  ConfigReader file(path);
  // What OpenCV's calibration sample (calibration.cpp) and tutorial
  // (camera_calibration.cpp) write beside the intrinsics.
  file.ignoreFields({"calibration_time", "nframes", "nr_of_frames", "board_width", "board_height", "square_size",
                     "aspectRatio", "aspect_ratio", "fix_aspect_ratio", "flags", "flagValue", "avg_reprojection_error",
                     "per_view_reprojection_errors", "extrinsic_parameters", "image_points", "grid_points"});
  if (file.readBool("fisheye_model", false))
    file.fail("fisheye_model", "fisheye calibrations are not supported; calibrate with the pinhole model");

  CameraIntrinsics camera;
  camera.width_px = file.readInt("image_width", kRequired, Range::atLeast(1));
  camera.height_px = file.readInt("image_height", kRequired, Range::atLeast(1));

  cv::Mat matrix = file.readMat("camera_matrix", 3, 3);
  // OpenCV's pinhole model with zero skew: [fx 0 cx; 0 fy cy; 0 0 1].
  if (matrix.at<double>(0, 1) != 0.0) file.fail("camera_matrix", "non-zero skew is not supported");
  if (matrix.at<double>(1, 0) != 0.0 || matrix.at<double>(2, 0) != 0.0 || matrix.at<double>(2, 1) != 0.0 ||
      matrix.at<double>(2, 2) != 1.0)
    file.fail("camera_matrix", "expected the form [fx 0 cx; 0 fy cy; 0 0 1]");
  camera.fx_px = matrix.at<double>(0, 0);
  camera.fy_px = matrix.at<double>(1, 1);
  camera.cx_px = matrix.at<double>(0, 2);
  camera.cy_px = matrix.at<double>(1, 2);

  cv::Mat distortion = file.readMat("distortion_coefficients", ConfigReader::kAnySize, ConfigReader::kAnySize);
  if (distortion.rows != 1 && distortion.cols != 1)
    file.fail("distortion_coefficients", "expected a 1xN or Nx1 vector, got " + std::to_string(distortion.rows) + "x" +
                                             std::to_string(distortion.cols));
  distortion = distortion.reshape(1, 1);
  int count = distortion.cols;
  if (count != 4 && count != 5 && count != 8 && count != 12 && count != 14)
    file.fail("distortion_coefficients", "expected 4 or 5 coefficients (k1 k2 p1 p2 [k3]), got " + std::to_string(count));
  for (int i = 5; i < count; ++i)
    if (distortion.at<double>(0, i) != 0.0)
      file.fail("distortion_coefficients",
                "coefficient " + std::to_string(i) + " is non-zero; only k1 k2 p1 p2 k3 are supported");
  for (int i = 0; i < std::min(count, 5); ++i) camera.distortion[static_cast<std::size_t>(i)] = distortion.at<double>(0, i);

  // Optional: files calibrated without a known lens position (a fixed-focus
  // camera, or OpenCV's own tools) have none. NaN stands for absent alone:
  // a NaN written in the file is refused as not finite.
  const double lens_position_dioptres =
      file.readDouble("lens_position_dioptres", std::numeric_limits<double>::quiet_NaN());
  if (!std::isnan(lens_position_dioptres)) camera.lens_position_dioptres = lens_position_dioptres;

  file.rejectUnknownFields();
  validateCameraIntrinsics(camera, path);
  return camera;
}

void saveCameraFile(const std::string& path, const CameraIntrinsics& camera) {
  validateCameraIntrinsics(camera, path);
  cv::FileStorage storage = openYamlForWriting(path);
  storage.writeComment("probelight camera intrinsics (OpenCV calibration layout)");
  storage << "image_width" << camera.width_px;
  storage << "image_height" << camera.height_px;
  cv::Mat matrix = (cv::Mat_<double>(3, 3) << camera.fx_px, 0, camera.cx_px, 0, camera.fy_px, camera.cy_px, 0, 0, 1);
  storage << "camera_matrix" << matrix;
  cv::Mat distortion(1, 5, CV_64F);
  for (int i = 0; i < 5; ++i) distortion.at<double>(0, i) = camera.distortion[static_cast<std::size_t>(i)];
  storage << "distortion_coefficients" << distortion;
  if (camera.lens_position_dioptres) storage << "lens_position_dioptres" << *camera.lens_position_dioptres;
  storage.release();
}

}  // namespace probelight::config
