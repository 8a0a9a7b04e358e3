// Seed D's exposure for the virtual lamp (issue 19): when the lamp's light
// on the ground would take a region of the frame past white, the whole
// frame (video, ground and object) is darkened as a shorter exposure would
// darken it, and the change ramps over time as a camera's auto exposure
// does. Region brightness comes from an integral image (cv::integral) of
// block means of the frame's linear luminance, so every window's mean
// costs four reads.
//
// Only the lamp's own addition is compensated: a region that is already at
// white without the lamp (a window, the room's own lamp) does not darken
// the frame, since the camera's auto exposure chose that.
#pragma once

#include <array>
#include <optional>
#include <vector>
#include <string>

#include <opencv2/core.hpp>

#include "capture/frame_source.hpp"
#include "core/types.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/virtual_lamp.hpp"
#include "stages/run_report.hpp"

namespace probelight {

// Pure: the largest mean over every window_blocks x window_blocks square of
// `blocks` (CV_64F, one value a block), from its integral image. A window
// larger than the image is the whole image.
double brightestWindowMean(const cv::Mat& blocks, int window_blocks);

// Pure: the exposure gain that keeps the lamp-lit frame's brightest region
// at what the room allowed: min(1, max(room_brightest, white_region_mean) /
// lit_brightest); 1 when either is not positive and finite.
double lampExposureTarget(double room_brightest, double lit_brightest, double white_region_mean);

// Pure: a gain moving toward its target over time, as auto exposure moves:
// in stops, first order, time constant tau: g <- g (target / g)^(1 - exp(-dt / tau)).
class ExposureRamp {
 public:
  explicit ExposureRamp(double time_constant_s) : time_constant_s_(time_constant_s) {}
  // A step not positive and finite leaves the gain; the first call after
  // construction starts from 1.
  double moveToward(double target, double step_s);
  double gain() const { return gain_; }

 private:
  double time_constant_s_;
  double gain_ = 1.0;
};

// The stage `lamp_exposure`: each shown frame with the lamp lighting, the
// frame's linear luminance in blocks (block_px square, 4 samples a block),
// with and without the lamp's light on the ground (ibl::lampToRoomRatio,
// unshadowed: the shadow only darkens), its brightest regions, and the
// ramp toward the gain. Skips: off (no lamp), no_object, no_room_light;
// while the lamp is not drawn the gain ramps back to 1.
class LampExposureStage {
 public:
  static constexpr const char* kStageName = "lamp_exposure";
  // A region of 1/8 of the frame's width whose mean passes 90% of white has
  // most of its pixels at or past white (a lit floor's texture varies by a
  // few percent).
  static constexpr double kWhiteRegionMean = 0.9;
  static constexpr int kBlockPx = 8;
  static constexpr double kRampTimeConstantS = 0.5;

  LampExposureStage(bool enabled, const ibl::VirtualLamp& lamp, const CameraIntrinsics& camera,
                    const ibl::CameraTransfer& transfer, RunReport& report);

  void run(bool object_shown, const PoseCamFromWorld& pose, const FrameBuffer& frame,
           const std::optional<glm::dvec3>& room_e_up, double time_s);
  void skip(const std::string& reason) { report_.recordStageSkip(kStageName, reason); }

  // The gain the frame is shown with (1: not darkened).
  double gain() const { return ramp_.gain(); }

 private:
  void skipAndRecover(const std::string& reason, double time_s);

  bool enabled_;
  ibl::VirtualLamp lamp_;
  CameraIntrinsics camera_;
  RunReport& report_;
  std::array<double, 256> decoded_{};  // the camera's code to linear light
  int blocks_x_ = 0, blocks_y_ = 0;
  std::vector<glm::dvec3> block_rays_cam_;  // through each block's centre, undistorted
  ExposureRamp ramp_{kRampTimeConstantS};
  std::optional<double> last_time_s_;
  bool lit_before_ = false;  // the lamp lit the frame before
  double lowest_gain_ = 1.0;
};

}  // namespace probelight
