#include "stages/lamp_exposure.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "ibl/camera_projection.hpp"

namespace probelight {

double brightestWindowMean(const cv::Mat& blocks, int window_blocks) {
  if (blocks.empty()) return 0.0;
  const int w = std::clamp(window_blocks, 1, blocks.cols), h = std::clamp(window_blocks, 1, blocks.rows);
  cv::Mat sums;
  cv::integral(blocks, sums, CV_64F);
  double brightest = 0.0;
  for (int y = 0; y + h <= blocks.rows; ++y)
    for (int x = 0; x + w <= blocks.cols; ++x) {
      const double sum = sums.at<double>(y + h, x + w) - sums.at<double>(y, x + w) - sums.at<double>(y + h, x) +
                         sums.at<double>(y, x);
      brightest = std::max(brightest, sum / (w * h));
    }
  return brightest;
}

double lampExposureTarget(double room_brightest, double lit_brightest, double white_region_mean) {
  if (!(lit_brightest > 0.0) || !std::isfinite(lit_brightest) || !std::isfinite(room_brightest)) return 1.0;
  return std::min(1.0, std::max(room_brightest, white_region_mean) / lit_brightest);
}

double ExposureRamp::moveToward(double target, double step_s) {
  if (!(target > 0.0) || !std::isfinite(target)) return gain_;
  if (!(step_s > 0.0) || !std::isfinite(step_s)) return gain_;
  const double moved = 1.0 - std::exp(-step_s / time_constant_s_);
  gain_ *= std::pow(target / gain_, moved);
  return gain_;
}

LampExposureStage::LampExposureStage(bool enabled, const ibl::VirtualLamp& lamp, const CameraIntrinsics& camera,
                                     const ibl::CameraTransfer& transfer, RunReport& report)
    : enabled_(enabled), lamp_(lamp), camera_(camera), report_(report) {
  for (int code = 0; code < 256; ++code) decoded_[static_cast<size_t>(code)] = ibl::decodeCameraValue(transfer, code / 255.0);
  blocks_x_ = std::max(1, camera.width_px / kBlockPx);
  blocks_y_ = std::max(1, camera.height_px / kBlockPx);
  if (!enabled_) return;
  block_rays_cam_.reserve(static_cast<size_t>(blocks_x_) * blocks_y_);
  for (int by = 0; by < blocks_y_; ++by)
    for (int bx = 0; bx < blocks_x_; ++bx)
      block_rays_cam_.push_back(ibl::pixelToCameraRay(
          camera, glm::dvec2((bx + 0.5) * kBlockPx - 0.5, (by + 0.5) * kBlockPx - 0.5)));
}

void LampExposureStage::run(bool object_shown, const PoseCamFromWorld& pose, const FrameBuffer& frame,
                            const std::optional<glm::dvec3>& room_e_up, double time_s) {
  if (!enabled_) return skip("off");
  // Without the lamp drawn (no tag, no fit yet), the frame's own exposure
  // comes back, ramping as it went.
  if (!object_shown) return skipAndRecover("no_object", time_s);
  if (!room_e_up || !(ibl::luminance(*room_e_up) > 0.0)) return skipAndRecover("no_room_light", time_s);
  const auto start = std::chrono::steady_clock::now();
  cv::Mat room(blocks_y_, blocks_x_, CV_64F), lit(blocks_y_, blocks_x_, CV_64F);
  const glm::dmat3 world_from_cam = glm::transpose(pose.R_cam_from_world);
  const glm::dvec3 eye = pose.cameraCenterWorld();
  const int quarter = kBlockPx / 4;
  for (int by = 0; by < blocks_y_; ++by)
    for (int bx = 0; bx < blocks_x_; ++bx) {
      // Four samples a block, at its quarter points.
      double sum = 0.0;
      for (int sy : {quarter, kBlockPx - 1 - quarter})
        for (int sx : {quarter, kBlockPx - 1 - quarter}) {
          const glm::u8vec3 rgb = frame.rgbAt(bx * kBlockPx + sx, by * kBlockPx + sy);
          sum += ibl::luminance(glm::dvec3(decoded_[rgb.r], decoded_[rgb.g], decoded_[rgb.b]));
        }
      const double mean = 0.25 * sum;
      double lamp_gain = 1.0;
      const glm::dvec3 ray_w = world_from_cam * block_rays_cam_[static_cast<size_t>(by) * blocks_x_ + bx];
      if (ray_w.z < 0.0) {
        const glm::dvec3 ground = eye + (-eye.z / ray_w.z) * ray_w;
        lamp_gain += ibl::luminance(ibl::lampToRoomRatio(lamp_, *room_e_up, glm::dvec2(ground)));
      }
      room.at<double>(by, bx) = mean;
      lit.at<double>(by, bx) = mean * lamp_gain;
    }
  const int window = std::max(1, blocks_x_ / 8);
  const double room_brightest = brightestWindowMean(room, window), lit_brightest = brightestWindowMean(lit, window);
  const double target = lampExposureTarget(room_brightest, lit_brightest, kWhiteRegionMean);
  // From the frame before: toward the target while the lamp was lit then,
  // toward 1 while it was not (the first frame it lights is shown at the
  // gain so far, and the darkening ramps in from there, as auto exposure
  // would).
  if (last_time_s_) ramp_.moveToward(lit_before_ ? target : 1.0, time_s - *last_time_s_);
  last_time_s_ = time_s;
  lit_before_ = true;
  lowest_gain_ = std::min(lowest_gain_, ramp_.gain());
  report_.recordStageMs(kStageName,
                        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  nlohmann::json& out = report_.extra["virtual_lamp"]["exposure"];
  out["gain"] = ramp_.gain();
  out["target"] = target;
  out["lowest_gain"] = lowest_gain_;
  out["brightest_region_mean"] = {{"room", room_brightest}, {"lit", lit_brightest}};
}

void LampExposureStage::skipAndRecover(const std::string& reason, double time_s) {
  if (last_time_s_) ramp_.moveToward(lit_before_ ? ramp_.gain() : 1.0, time_s - *last_time_s_);
  last_time_s_ = time_s;
  lit_before_ = false;
  skip(reason);
}

}  // namespace probelight
