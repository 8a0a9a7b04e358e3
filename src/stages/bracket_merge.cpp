#include "stages/bracket_merge.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "ibl/probe_to_cube.hpp"
#include "stages/bracket_motion.hpp"

namespace probelight {
namespace {

std::string fixed(double value, int digits) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(digits);
  out << value;
  return out.str();
}

template <typename Visit>
void forEachBallPixel(const ibl::ProbeOutline& outline, int width, int height, Visit visit) {
  const int x0 = std::max(0, static_cast<int>(std::floor(outline.min_px.x)));
  const int x1 = std::min(width - 1, static_cast<int>(std::ceil(outline.max_px.x)));
  const int y0 = std::max(0, static_cast<int>(std::floor(outline.min_px.y)));
  const int y1 = std::min(height - 1, static_cast<int>(std::ceil(outline.max_px.y)));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x)
      if (glm::length(glm::dvec2(x, y) - outline.center_px) <= outline.radius_px) visit(x, y);
}

}  // namespace

BallPixelCodes ballPixelCodes(const ImageRGB8& image, const ibl::ProbeOutline& outline,
                              const ibl::HdrMergeSettings& merge) {
  BallPixelCodes codes;
  forEachBallPixel(outline, image.width, image.height, [&](int x, int y) {
    const std::uint8_t* p = image.row(y) + 3 * x;
    const int high = std::max({p[0], p[1], p[2]}), low = std::min({p[0], p[1], p[2]});
    if (high >= merge.clip_code) ++codes.clipped;
    if (low > merge.dark_code && high < merge.clip_code) ++codes.measured;
  });
  return codes;
}

BracketMergeResult mergeBracketProbe(const ImageRGB8& reference, std::vector<BracketCandidate> candidates,
                                     const BracketSetup& setup,
                                     const std::function<void(const BracketCandidate&, const std::string&)>& refused) {
  BracketMergeResult result;
  auto refuse = [&](const BracketCandidate& candidate, const std::string& why) {
    result.frames.push_back({{"frame", candidate.label}, {"ev", candidate.ev}, {"used", false}, {"reason", why}});
    if (refused) refused(candidate, why);
  };
  std::stable_sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) { return a.ev > b.ev; });
  std::vector<const BracketCandidate*> accepted;
  std::vector<ibl::MirrorBallView> accepted_views;
  ibl::MirrorBallView last_view = setup.view;  // the pose of the frame before
  // One tracker for all, seeded with the reference frame's pose: it
  // searches only a window around the tag (a still camera finds it there at
  // once), and the whole frame only where the window does not show it.
  std::optional<tracking::TagTracker> own_tracker;
  if (!setup.tracker) own_tracker.emplace(setup.detector, setup.rig, setup.view.camera);
  tracking::TagTracker& tracker = setup.tracker ? *setup.tracker : *own_tracker;
  tracker.seed(setup.view.pose);
  // Where the tag is bright enough to be found, its pose; all tracked
  // first, so that a dark frame can take the motion the later ones show too.
  const auto rightSize = [&](const BracketCandidate& candidate) {
    return candidate.rgb.width == reference.width && candidate.rgb.height == reference.height;
  };
  std::vector<tracking::TagTrackResult> tracks(candidates.size());
  BracketMotion motion(setup.view.pose, setup.reference_time_s);
  double last_time_s = setup.reference_time_s;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    if (!rightSize(candidates[k])) continue;
    std::vector<std::uint8_t> luma;
    lumaFromRgb(candidates[k].rgb, luma);
    tracks[k] = tracker.track(luma.data(), candidates[k].rgb.width, candidates[k].rgb.height, candidates[k].rgb.width);
    if (tracks[k].found) motion.addTracked(candidates[k].time_s, tracks[k].pose);
    if (std::isfinite(candidates[k].time_s)) last_time_s = std::max(last_time_s, candidates[k].time_s);
  }
  auto ballShiftPx = [&](const PoseCamFromWorld& pose) {
    const ibl::ProbeOutline there =
        ibl::computeProbeOutline(ibl::MirrorBallView{setup.view.camera, pose, setup.view.center_w, setup.view.radius_m});
    return there.valid ? glm::length(there.center_px - setup.outline.center_px) : INFINITY;
  };
  // A camera still to within the pose's noise keeps the reference's pose
  // (a dim tag's pose scatters more than a still camera moves); one whose
  // tagged frames show it moving on beyond that by the bracket's last frame
  // is followed.
  const std::optional<PoseCamFromWorld> pose_at_end = motion.poseAt(last_time_s);
  const bool camera_moves = setup.untracked_take_previous_pose && pose_at_end &&
                            ballShiftPx(*pose_at_end) > kBracketPoseNoisePx;
  const ImageRGB8* previous = &reference;
  double previous_ev = 0.0;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const BracketCandidate& candidate = candidates[k];
    if (!rightSize(candidate)) {
      refuse(candidate, "it is " + std::to_string(candidate.rgb.width) + "x" + std::to_string(candidate.rgb.height) +
                            ", the reference frame " + std::to_string(reference.width) + "x" +
                            std::to_string(reference.height));
      continue;
    }
    const BallPixelCodes codes = ballPixelCodes(candidate.rgb, setup.outline, setup.merge);
    if (codes.measured == 0) {
      refuse(candidate, codes.clipped > 0 ? "the ball is clipped everywhere in it" : "the ball is black everywhere in it");
      continue;
    }
    const tracking::TagTrackResult& track = tracks[k];
    std::string pose_check = setup.untracked_take_previous_pose
                                 ? "tag too dark to find: merged with the pose of the frame before"
                                 : "tag too dark to find: merged with the reference frame's pose";
    ibl::MirrorBallView view = setup.untracked_take_previous_pose ? last_view : setup.view;
    std::optional<double> moved_px;
    if (track.found) {
      view = ibl::MirrorBallView{setup.view.camera, track.pose, setup.view.center_w, setup.view.radius_m};
      moved_px = ballShiftPx(track.pose);
    } else if (const std::optional<PoseCamFromWorld> predicted = motion.poseAt(candidate.time_s);
               camera_moves && predicted) {
      view = ibl::MirrorBallView{setup.view.camera, *predicted, setup.view.center_w, setup.view.radius_m};
      moved_px = ballShiftPx(*predicted);
      pose_check = "tag too dark to find: merged with the pose the camera's motion puts it at, ball " +
                   fixed(*moved_px, 2) + " px from the reference frame's";
    }
    if (moved_px) {
      // The camera must not have moved far: the ball's rim falls on other
      // directions in each frame.
      if (!(*moved_px <= kBracketMaxBallShiftRadii * setup.outline.radius_px)) {
        const std::string where = std::isfinite(*moved_px)
                                      ? "is " + fixed(*moved_px, 1) + " px from where the reference frame has it"
                                      : "is out of the camera's view";
        refuse(candidate, "the camera moved too far between exposures: the ball " + where + " (a tenth of its radius, " +
                              fixed(kBracketMaxBallShiftRadii * setup.outline.radius_px, 1) + " px, is the most)");
        continue;
      }
      if (track.found && camera_moves) {
        pose_check = "merged with its own pose (the camera moves): ball " + fixed(*moved_px, 2) +
                     " px from the reference frame's";
      } else if (track.found && *moved_px <= kBracketPoseNoisePx) {
        view = setup.view;
        pose_check = "ball " + fixed(*moved_px, 2) + " px from the reference frame's: within the pose's noise, merged with its pose";
      } else if (track.found) {
        pose_check = "merged with its own pose: ball " + fixed(*moved_px, 2) + " px from the reference frame's";
      }
    }
    // The exposure the pixels show against the one claimed.
    const std::optional<double> ratio = ibl::measureExposureRatio(*previous, candidate.rgb, setup.merge);
    nlohmann::json entry = {{"frame", candidate.label}, {"ev", candidate.ev}, {"used", true}, {"pose", pose_check}};
    if (ratio) {
      const double measured_ev = previous_ev + std::log2(*ratio);
      entry["measured_ev"] = measured_ev;
      if (std::abs(measured_ev - candidate.ev) > kBracketMaxEvDisagreement) {
        refuse(candidate, "its pixels say EV " + fixed(measured_ev, 1) + ", not " + fixed(candidate.ev, 1));
        continue;
      }
    } else {
      entry["measured_ev"] = nullptr;  // nothing well exposed in both frames: not checked
    }
    result.frames.push_back(entry);
    accepted.push_back(&candidate);
    accepted_views.push_back(view);
    last_view = view;
    previous = &candidate.rgb;
    previous_ev = candidate.ev;
  }
  result.used = static_cast<int>(accepted.size());
  if (accepted.empty()) {
    result.status = "no usable bracket frame";
    return result;
  }
  std::vector<ibl::BracketView> frames{{&reference, 0.0, setup.view}};
  for (std::size_t k = 0; k < accepted.size(); ++k) frames.push_back({&accepted[k]->rgb, accepted[k]->ev, accepted_views[k]});
  ibl::ProbeToCubeParams params;
  params.face_size = setup.face_size;
  params.probe_reflectance = setup.rig.probe_reflectance;
  params.camera_transfer = setup.merge.camera_transfer;
  params.samples_per_axis = 4;
  std::vector<std::uint8_t>& still_clipped = result.still_clipped;
  result.hdr_cube = ibl::bracketToCubeMap(frames, setup.merge, params, &still_clipped);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (int y = 0; y < setup.face_size; ++y)
      for (int x = 0; x < setup.face_size; ++x)
        if (still_clipped[static_cast<std::size_t>(face) * setup.face_size * setup.face_size +
                          static_cast<std::size_t>(y) * setup.face_size + x])
          result.still_clipped_sr += ibl::cubeTexelSolidAngle(x, y, setup.face_size);
  result.status = result.still_clipped_sr > 0.0
                      ? "merged; " + fixed(result.still_clipped_sr, 4) +
                            " sr clipped even in the shortest exposure (a lower bound there)"
                      : "merged";
  return result;
}

}  // namespace probelight
