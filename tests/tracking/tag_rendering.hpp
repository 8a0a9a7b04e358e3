// A small, independent renderer of a printed AprilTag seen by a pinhole
// camera with OpenCV distortion, for tests. It uses only libapriltag's
// apriltag_to_image and OpenCV, not the tracker's maths, so a convention
// error in the tracker cannot hide in it.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
#include <glm/glm.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/types.hpp"

namespace probelight::testing {

// Camera pose looking at the world origin from `eye_w`, with image "up" as
// close to `up_w` as the view direction allows.
inline PoseCamFromWorld lookAtPose(const glm::dvec3& eye_w, const glm::dvec3& target_w, const glm::dvec3& up_w) {
  glm::dvec3 forward = glm::normalize(target_w - eye_w);     // camera +z
  glm::dvec3 right = glm::normalize(glm::cross(forward, up_w));  // camera +x
  glm::dvec3 down = glm::cross(forward, right);               // camera +y
  glm::dmat3 R_world_from_cam(right, down, forward);          // columns: camera axes in W
  PoseCamFromWorld pose;
  pose.R_cam_from_world = glm::transpose(R_world_from_cam);
  pose.t_cam_from_world = -pose.R_cam_from_world * eye_w;
  return pose;
}

inline std::vector<glm::dvec2> projectWorldPoints(const std::vector<glm::dvec3>& points_w, const PoseCamFromWorld& pose,
                                                  const CameraIntrinsics& camera) {
  std::vector<cv::Point3d> camera_points;
  for (const glm::dvec3& p : points_w) {
    glm::dvec3 c = pose.toCamera(p);
    camera_points.emplace_back(c.x, c.y, c.z);
  }
  cv::Matx33d K(camera.fx_px, 0, camera.cx_px, 0, camera.fy_px, camera.cy_px, 0, 0, 1);
  std::vector<double> distortion(camera.distortion.begin(), camera.distortion.end());
  std::vector<cv::Point2d> image;
  cv::projectPoints(camera_points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, distortion, image);
  std::vector<glm::dvec2> result;
  for (const cv::Point2d& p : image) result.emplace_back(p.x, p.y);
  return result;
}

// The printed image of tag36h11 `id`, row 0 at its top, `texels_per_cell`
// texels per tag cell (nearest-neighbour, so edges stay sharp).
inline cv::Mat printedTag36h11(int id, int texels_per_cell, int* cells_total, int* cells_at_border) {
  apriltag_family_t* family = tag36h11_create();
  image_u8_t* tag = apriltag_to_image(family, id);
  cv::Mat cells(tag->height, tag->width, CV_8U, tag->buf, static_cast<size_t>(tag->stride));
  cv::Mat texture;
  cv::resize(cells, texture, {}, texels_per_cell, texels_per_cell, cv::INTER_NEAREST);
  *cells_total = family->total_width;
  *cells_at_border = family->width_at_border;
  // image_u8_destroy lives in libapriltag-utils, which apriltag::apriltag does
  // not link; apriltag_to_image allocates the image and its pixels with calloc.
  std::free(tag->buf);
  std::free(tag);
  tag36h11_destroy(family);
  return texture;
}

struct TagScene {
  CameraIntrinsics camera;
  PoseCamFromWorld pose;
  double tag_size_m = 0.10;
  int tag_id = 0;
  std::uint8_t background = 110;  // grey table around the white margin
  double noise_sigma = 0.0;       // grey levels, Gaussian
  unsigned noise_seed = 1;
};

// Renders the luma frame: 3x3 supersampling of the exact (distorted)
// projection, box-filtered down, so edges are anti-aliased like a camera's.
inline cv::Mat renderTagScene(const TagScene& scene) {
  constexpr int kTexelsPerCell = 48;
  constexpr int kSupersample = 3;
  int cells_total = 0, cells_at_border = 0;
  cv::Mat texture = printedTag36h11(scene.tag_id, kTexelsPerCell, &cells_total, &cells_at_border);
  const CameraIntrinsics& cam = scene.camera;

  // Texel (u, v) centre (OpenCV convention) -> world plane point (x, y, 1).
  // The black border's outer edge spans cells [1, 9] of 10 for tag36h11 and
  // must land on x, y = +-s/2; texture row 0 is the printed top (+Y).
  double metres_per_texel = scene.tag_size_m / (kTexelsPerCell * cells_at_border);
  double half_total_m = 0.5 * cells_total * kTexelsPerCell * metres_per_texel;
  cv::Matx33d world_from_texel(metres_per_texel, 0, 0.5 * metres_per_texel - half_total_m,  //
                               0, -metres_per_texel, half_total_m - 0.5 * metres_per_texel,  //
                               0, 0, 1);
  const glm::dmat3& R = scene.pose.R_cam_from_world;
  const glm::dvec3& t = scene.pose.t_cam_from_world;
  // Normalised camera coordinates of a plane point: [r1 r2 t] (glm is column-major).
  cv::Matx33d normalized_from_world(R[0][0], R[1][0], t.x,  //
                                    R[0][1], R[1][1], t.y,  //
                                    R[0][2], R[1][2], t.z);
  cv::Matx33d texel_from_normalized = (normalized_from_world * world_from_texel).inv();

  // Only the tag's neighbourhood needs the per-pixel inverse mapping.
  double margin_m = half_total_m * 1.3;
  std::vector<glm::dvec2> outline = projectWorldPoints(
      {{-margin_m, -margin_m, 0}, {margin_m, -margin_m, 0}, {margin_m, margin_m, 0}, {-margin_m, margin_m, 0}},
      scene.pose, cam);
  double min_x = 1e9, min_y = 1e9, max_x = -1e9, max_y = -1e9;
  for (const glm::dvec2& p : outline) {
    min_x = std::min(min_x, p.x), max_x = std::max(max_x, p.x);
    min_y = std::min(min_y, p.y), max_y = std::max(max_y, p.y);
  }
  cv::Rect box(cv::Point(std::max(0, int(std::floor(min_x)) - 2), std::max(0, int(std::floor(min_y)) - 2)),
               cv::Point(std::min(cam.width_px, int(std::ceil(max_x)) + 3), std::min(cam.height_px, int(std::ceil(max_y)) + 3)));

  cv::Mat frame(cam.height_px, cam.width_px, CV_8U, cv::Scalar(scene.background));
  if (box.area() > 0) {
    int w = box.width * kSupersample, h = box.height * kSupersample;
    std::vector<cv::Point2d> distorted_px;
    distorted_px.reserve(static_cast<size_t>(w) * static_cast<size_t>(h));
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)  // sub-sample centres in frame pixel coordinates
        distorted_px.emplace_back(box.x + (x + 0.5) / kSupersample - 0.5, box.y + (y + 0.5) / kSupersample - 0.5);
    cv::Matx33d K(cam.fx_px, 0, cam.cx_px, 0, cam.fy_px, cam.cy_px, 0, 0, 1);
    std::vector<double> distortion(cam.distortion.begin(), cam.distortion.end());
    std::vector<cv::Point2d> normalized;
    cv::undistortPoints(distorted_px, normalized, K, distortion, cv::noArray(), cv::noArray(),
                        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 1e-12));
    cv::Mat map_x(h, w, CV_32F), map_y(h, w, CV_32F);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const cv::Point2d& n = normalized[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)];
        cv::Vec3d texel = texel_from_normalized * cv::Vec3d(n.x, n.y, 1.0);
        map_x.at<float>(y, x) = static_cast<float>(texel[0] / texel[2]);
        map_y.at<float>(y, x) = static_cast<float>(texel[1] / texel[2]);
      }
    cv::Mat supersampled, patch;
    cv::remap(texture, supersampled, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(scene.background));
    cv::resize(supersampled, patch, box.size(), 0, 0, cv::INTER_AREA);
    patch.copyTo(frame(box));
  }
  if (scene.noise_sigma > 0) {
    cv::Mat noise(frame.size(), CV_32F);
    cv::RNG rng(scene.noise_seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, scene.noise_sigma);
    cv::Mat noisy;
    frame.convertTo(noisy, CV_32F);
    noisy += noise;
    noisy.convertTo(frame, CV_8U);  // saturating
  }
  return frame;
}

}  // namespace probelight::testing
