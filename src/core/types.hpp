// Plain data shared by every layer: calibration, rig geometry, poses, images.
// No behaviour lives here beyond trivial accessors, so that the simulator (the
// oracle) and the pipeline (what it checks) can share vocabulary without
// sharing maths.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace probelight {

// Pinhole camera with OpenCV's 5-term radial-tangential distortion
// (k1, k2, p1, p2, k3), exactly as cv::calibrateCamera writes camera.yaml.
// Camera frame: x right, y down, z forward.
struct CameraIntrinsics {
  int width_px = 640;
  int height_px = 480;
  double fx_px = 525.0;
  double fy_px = 525.0;
  double cx_px = 319.5;
  double cy_px = 239.5;
  std::array<double, 5> distortion{0, 0, 0, 0, 0};  // k1 k2 p1 p2 k3
  // The lens position the intrinsics were calibrated at, in dioptres
  // (1 / focus distance in metres; libcamera's LensPosition): a lens that
  // focuses elsewhere changes the focal length and distortion. nullopt: not
  // known, and the camera's own focus is left alone.
  std::optional<double> lens_position_dioptres;
};

// The largest lens position accepted (dioptres): 1 cm focus distance, ten
// times closer than the Camera Module 3 focuses (10 cm; libcamera's
// LensPosition range for its IMX708 is 0..32). Past it a value is a slip,
// such as a focus distance in millimetres written for dioptres.
constexpr double kMaxLensPositionDioptres = 100.0;

// Physical set-up: the marker and the mirror ball. World frame W is the tag's
// frame: origin at the tag centre, +X toward the right edge of the printed tag
// image, +Y toward its top edge, +Z up out of the ground.
struct RigGeometry {
  std::string tag_family = "tag36h11";
  int tag_id = 0;
  double tag_size_m = 0.10;  // outer edge of the black border
  glm::dvec3 probe_center_w{0.12, 0.0, 0.08};
  double probe_radius_m = 0.03;
  double probe_reflectance = 1.0;  // 0..1; chrome is about 0.6-0.8
  // Diffuse reflectance of the tag's printed white (ibl/white_reference.hpp):
  // plain office paper under laser toner is about 0.8-0.9.
  double tag_white_albedo = 0.85;
  // The ball's post (ibl/post_reference.hpp), where it stands on one: a
  // vertical cylinder of this radius from the ground up to the ball, matte,
  // of diffuse reflectance post_albedo. Painted so, it is a second diffuse
  // reference beside the tag's white border. 0 (either): no post to read.
  double post_radius_m = 0.0;
  double post_albedo = 0.0;
};

// Rigid transform taking world points into the camera frame:
// p_cam = R_cam_from_world * p_w + t_cam_from_world (metres).
struct PoseCamFromWorld {
  glm::dmat3 R_cam_from_world{1.0};
  glm::dvec3 t_cam_from_world{0.0};

  glm::dvec3 toCamera(const glm::dvec3& p_w) const { return R_cam_from_world * p_w + t_cam_from_world; }
  glm::dvec3 cameraCenterWorld() const { return -glm::transpose(R_cam_from_world) * t_cam_from_world; }
};

// The angle of the rotation between orientations a and b (of a * b^T, or
// a^T * b: the same angle), in degrees. atan2 of the sine and cosine parts
// keeps precision at small angles, where acos of the trace alone bottoms out
// near 1e-6 degrees.
double rotationAngleDeg(const glm::dmat3& a, const glm::dmat3& b);

// An 8-bit plane read in place (the detector's luma).
struct LumaView {
  const std::uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  int stride = 0;  // bytes per row
};

// The largest image side probelight accepts anywhere: camera.yaml's sizes
// and the frames it reads (8K; the kiosk's camera modes are far smaller).
constexpr int kMaxImageSidePx = 8192;

// Tightly packed 8-bit RGB image (camera-encoded, sRGB by default).
struct ImageRGB8 {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  // row-major, 3 bytes per pixel, no padding

  void resize(int w, int h) {
    width = w;
    height = h;
    pixels.assign(static_cast<size_t>(w) * static_cast<size_t>(h) * 3u, 0);
  }
  std::uint8_t* row(int y) { return pixels.data() + static_cast<size_t>(y) * static_cast<size_t>(width) * 3u; }
  const std::uint8_t* row(int y) const { return pixels.data() + static_cast<size_t>(y) * static_cast<size_t>(width) * 3u; }
  bool empty() const { return width <= 0 || height <= 0; }
};

// Linear RGB floats, row-major: a radiance image merged from an exposure
// bracket, in the reference exposure's camera linear units (may exceed 1).
struct ImageRGBF {
  int width = 0;
  int height = 0;
  std::vector<glm::vec3> pixels;

  void resize(int w, int h) {
    width = w;
    height = h;
    pixels.assign(static_cast<size_t>(w) * static_cast<size_t>(h), glm::vec3(0.0f));
  }
  glm::vec3& at(int x, int y) { return pixels[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)]; }
  const glm::vec3& at(int x, int y) const {
    return pixels[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)];
  }
  bool empty() const { return width <= 0 || height <= 0; }
};

}  // namespace probelight

namespace probelight {

// What the simulator knows about a frame it rendered. Carried with sim frames
// so that the run report can measure error against truth; real sources leave
// it empty.
struct FrameTruth {
  PoseCamFromWorld pose;
  glm::dvec2 probe_center_px{0.0};  // centre of the ball's image outline
  double probe_radius_px = 0.0;     // radius of the circle with the outline's area
  double exposure = 1.0;            // camera linear value = radiance * exposure (before clipping)
  bool tag_fully_visible = false;
  bool probe_fully_visible = false;
};

// BT.601 luma of one pixel's R'G'B' codes: 0.299, 0.587, 0.114 in 14-bit
// fixed point, rounded (OpenCV's RGB2GRAY).
inline std::uint8_t lumaCodeOfRgb(std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  constexpr std::uint32_t kR = 4899, kG = 9617, kB = 1868, kHalf = 1u << 13;
  return static_cast<std::uint8_t>((kR * r + kG * g + kB * b + kHalf) >> 14);
}

// BT.601 luma of sRGB bytes (OpenCV's RGB->GRAY fixed-point weights and
// rounding), packed: stride = width. For the sim and image sources, which
// give RGB; the libcamera source has a Y' plane already.
void lumaFromRgb(const ImageRGB8& rgb, std::vector<std::uint8_t>& luma);

}  // namespace probelight
