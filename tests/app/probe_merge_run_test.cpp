// The kiosk's probe over views (environment_maps.merge_views) through the
// real binary on the simulated camera, against the simulator's own truth:
// a lamp switched on shows at once, a still room stops remaking its maps,
// and a moving camera fills what one view hides behind its ball. Each scene
// is rendered once: its variants (a single view, maps never remade) replay
// its recording, truth included.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "binary_test_support.hpp"

namespace probelight {
namespace {

namespace fs = std::filesystem;

using testing::CommandResult;

class ProbeMergeRun : public testing::BinaryTest {
 protected:
  ProbeMergeRun() : BinaryTest("probe_merge_run") {}

  // One run with `yaml` as its config; its report. The simulator renders
  // it, and records it into DIR/<name>.rec for replayWith.
  nlohmann::json runWith(const std::string& name, const std::string& yaml, const std::string& flags) {
    const fs::path config = dir_ / (name + ".yaml");
    std::ofstream(config) << yaml;
    const fs::path out = dir_ / name;
    const CommandResult result = run("run --save-every 0 " + flags + " --config " + config.string() + " --out " +
                                     out.string() + " --record " + (dir_ / (name + ".rec")).string());
    EXPECT_EQ(result.exit_status, 0) << result.stderr_text;
    return readReport(out);
  }

  // The frames runWith(`recorded`) rendered, replayed with `yaml` as the
  // config (the same world: only the pipeline's settings differ), its
  // report measured against the same truth (the recording keeps it). The
  // scene is rendered once for all its variants. A variant whose pipeline
  // would ask the camera for other exposures than the recorded run did
  // (another bracket) cannot be replayed: that fails here, saying so.
  nlohmann::json replayWith(const std::string& name, const std::string& yaml, const std::string& recorded,
                            const nlohmann::json& recorded_report) {
    const fs::path config = dir_ / (name + ".yaml");
    std::ofstream(config) << yaml;
    const fs::path out = dir_ / name;
    const CommandResult result = run("run --save-every 0 --source recording --recording " +
                                     (dir_ / (recorded + ".rec")).string() + " --frames 0 --config " +
                                     config.string() + " --out " + out.string());
    EXPECT_EQ(result.exit_status, 0) << result.stderr_text;
    const nlohmann::json report = readReport(out);
    EXPECT_EQ(report["frames"], recorded_report["frames"]) << name;
    EXPECT_EQ(report["counters"].value("frames_in_bracket", 0), recorded_report["counters"].value("frames_in_bracket", 0))
        << name << ": its pipeline bracketed other frames than " << recorded << "'s: render it live";
    EXPECT_TRUE(report["map_updates"].contains("truth_checks")) << name << ": the replay lost the truth";
    return report;
  }
};

// A truth check of `report` on `frame` (the truth monitor checks every
// 10th frame): `measure` is diffuse_irradiance_rel_error_vs_clipped (the
// diffuse map against the irradiance an 8-bit camera can know) or
// lit_irradiance_rel_error_vs_hdr (the diffuse map and the clipped lights,
// what the object's diffuse term is lit with, against the whole
// irradiance).
double errorAt(const nlohmann::json& report, int frame, const char* measure) {
  for (const nlohmann::json& check : report["map_updates"]["truth_checks"])
    if (check["frame"] == frame) return check[measure].get<double>();
  ADD_FAILURE() << "no truth check on frame " << frame;
  return std::nan("");
}

constexpr const char* kDiffuseVsClipped = "diffuse_irradiance_rel_error_vs_clipped";
constexpr const char* kLitVsHdr = "lit_irradiance_rel_error_vs_hdr";

// A lamp switched on at frame 40 with the camera still. The merged probe
// replaces every texel whose change beats its noise within the frame, so
// its maps show the lamp on the lamp's first frame. A camera without
// exposure control, so that no bracket's measurement sits in the maps and
// the 8-bit truth is the measure (with one, the maps keep the bracket's
// texels at the clip where an 8-bit view averages a clipped light with
// what is around it: the split between the maps and the clipped lights
// moves, not their sum; the test below checks that sum).
TEST_F(ProbeMergeRun, ALampSwitchedOnShowsInItsFirstFrame) {
  const std::string lamp = "sim:\n  lamp_on_frame: 40\n  exposure_control: false\n";
  const nlohmann::json merged = runWith("merged", lamp, "--frames 51 --path static");
  const nlohmann::json single =
      replayWith("single", lamp + "environment_maps:\n  merge_views: false\n", "merged", merged);
  // Control: maps never remade after the first show how far the lamp moves
  // the light (else the test would prove nothing).
  const nlohmann::json frozen = replayWith(
      "frozen", lamp + "map_updates:\n  change_threshold_code: 255\n  max_age_frames: 100000\n", "merged", merged);
  const double lamp_effect = errorAt(frozen, 40, kDiffuseVsClipped) - errorAt(frozen, 30, kDiffuseVsClipped);
  ASSERT_GT(lamp_effect, 0.1) << "the lamp did not change the light";
  // On the lamp's first frame, what is left of its effect is at most a
  // tenth (measured: 0.07 points of 25).
  EXPECT_LT(errorAt(merged, 40, kDiffuseVsClipped) - errorAt(merged, 30, kDiffuseVsClipped), 0.1 * lamp_effect);
  // And never worse than one view alone. The probe's steady estimate
  // averages ~30 views where a single view has one noise sample; 1 point
  // is five times the truth check's spread between noise samples (< 0.2
  // points in StaticCameraKeepsTheMapsYetStaysAccurateAndSteadier).
  for (int frame : {30, 40, 50})
    EXPECT_LT(errorAt(merged, frame, kDiffuseVsClipped), errorAt(single, frame, kDiffuseVsClipped) + 0.01)
        << "frame " << frame;
  EXPECT_GE(merged["probe_merge"]["texels_changed"].get<long>(), 1) << merged["probe_merge"].dump();
  EXPECT_FALSE(single.contains("probe_merge")) << "merge_views: false has no probe";
}

// A still camera in still light, the maps remade from every frame
// (max_age_frames 1), with the start-up fit's bracket in the probe. Once
// the probe has converged, a view moves the irradiance by less than half a
// display code and no texel by a noise sigma, and the diffuse maps are not
// remade ("probe unchanged"): the skip logic holds with the merge. And what
// the object is lit with (the maps and the clipped lights) is as close to
// the whole irradiance as a single view's, or closer.
TEST_F(ProbeMergeRun, AStillRoomStopsRemakingTheMapsOnceTheProbeHasSettled) {
  const std::string every_frame = "map_updates:\n  max_age_frames: 1\n";
  const nlohmann::json report = runWith("still", every_frame, "--frames 40 --path static");
  const nlohmann::json single =
      replayWith("single", every_frame + "environment_maps:\n  merge_views: false\n", "still", report);
  const nlohmann::json& probe = report["probe_merge"];
  ASSERT_GE(probe["views"].get<long>(), 30) << "max_age_frames 1 remakes the reflection map every frame";
  EXPECT_EQ(probe["brackets"], 1) << probe.dump();
  EXPECT_GE(probe["views_remaking_nothing"].get<long>(), probe["views"].get<long>() / 2) << probe.dump();
  EXPECT_GE(report["stages"]["diffuse_blur"]["skip_reasons"]["probe unchanged"].get<long>(),
            probe["views_remaking_nothing"].get<long>())
      << report["stages"]["diffuse_blur"].dump();
  // Measured: 0.9%, 1.0%, 1.0% for the probe (1.3%, 1.9%, 2.3% before the
  // footprint check kept the bracket's texels at the clipped lights'
  // edges), 2.3% each for the single view. Half a point is the spread
  // between noise samples (< 0.2) with room.
  for (int frame : {10, 20, 30})
    EXPECT_LT(errorAt(report, frame, kLitVsHdr), errorAt(single, frame, kLitVsHdr) + 0.005) << "frame " << frame;
}

// A camera moving about the studio (slow wobble), the room unchanged: the
// soft boxes clip in every 8-bit view, and the start-up fit's bracket
// measured them. The GPU's 8-bit map samples each texel at its centre where
// the bracket averaged its area, so at the boxes' edges later views read
// less than the bracket beside clipped pixels; those readings are lower
// bounds (a clipped pixel within the texel's footprint), not a change, and
// what the object is lit with must not drift from the fit's. Before the
// footprint check the probe went from 1.8% at frame 20 to 4.8% at frame 80
// against the single view's 1.8-3.1%; measured now: 1.0-1.1% throughout.
// Half a point is the spread of the single view's frame-to-frame error.
TEST_F(ProbeMergeRun, AMovingCameraKeepsWhatTheBracketMeasured) {
  const nlohmann::json report = runWith("moving", "sim:\n  env: studio\n", "--frames 90 --path slow_wobble");
  const nlohmann::json single =
      replayWith("moving_single", "sim:\n  env: studio\nenvironment_maps:\n  merge_views: false\n", "moving", report);
  EXPECT_EQ(report["probe_merge"]["brackets"], 1) << report["probe_merge"].dump();
  const double after_fit = errorAt(report, 20, kLitVsHdr);
  for (int frame : {40, 50, 60, 70, 80}) {
    EXPECT_LT(errorAt(report, frame, kLitVsHdr), after_fit + 0.005) << "drifted by frame " << frame;
    EXPECT_LT(errorAt(report, frame, kLitVsHdr), errorAt(single, frame, kLitVsHdr) + 0.005) << "frame " << frame;
  }
}

// The sunrise turned so that its sun lies behind the ball at the start
// (scripts/probe-merge-table.sh's configuration), and a hand-held sweep
// (12 degrees a second at the start). Two things went wrong here:
//  - The start-up bracket's darkest frames, where the tag is too dark to
//    find and only the sun shows, took the reference frame's pose though
//    the camera had moved on 1-1.7 px of ball: the sun they measure was
//    misplaced (13.5% at frame 20, against 3.7% for a still camera). They
//    now take the pose the tagged frames' motion puts them at
//    (stages/bracket_motion): 1.8%.
//  - The bracket saw the sun in the ball's rim, smeared over many texels;
//    later views that see those directions at least as sharply read sky
//    there and replace the smear, and the clipped-light follower, counting
//    the texels still clipping, took 13% of the sun away though it never
//    changed (4.9% by frame 180, the single view 2.0%). Texels so resolved
//    now leave the light instead of dimming it: 2.7%, the share 0.97.
TEST_F(ProbeMergeRun, AHandHeldSweepKeepsTheSunItsBracketMeasured) {
  const std::string sunrise = "sim:\n  env: sunrise\n  environment_rotation_deg: 210\n";
  const nlohmann::json sweep = runWith("sweep", sunrise, "--frames 200 --path hand_held_sweep");
  const nlohmann::json still = runWith("still", sunrise, "--frames 30 --path static");
  const nlohmann::json single =
      replayWith("sweep_single", sunrise + "environment_maps:\n  merge_views: false\n", "sweep", sweep);
  int moved_frames = 0;
  for (const nlohmann::json& frame : sweep["hdr"]["frames"])
    if (frame.value("pose", "").find("the camera's motion puts it at") != std::string::npos) ++moved_frames;
  EXPECT_GE(moved_frames, 1) << sweep["hdr"]["frames"].dump();
  // As good as the same world from a still camera, to a point (the truth
  // check's spread between noise samples is under 0.2 points).
  EXPECT_LT(errorAt(sweep, 20, kLitVsHdr), errorAt(still, 20, kLitVsHdr) + 0.01);
  // The sun never changes: what is left of the fit's clipped light, at
  // most 5% gone (edge texels the views read below the clip at the same
  // sharpness as the bracket: they may be a dimmed edge, and count so).
  const nlohmann::json& shares = sweep["clipped_lights_now"]["still_clipping_share"];
  ASSERT_FALSE(shares.empty()) << sweep["clipped_lights_now"].dump();
  for (const nlohmann::json& share : shares) EXPECT_GE(share.get<double>(), 0.95);
  // And the probe stays within a point of one view once both have settled
  // (the single view's clipped light leaves it around frame 70: 15%).
  for (int frame = 90; frame <= 190; frame += 20)
    EXPECT_LT(errorAt(sweep, frame, kLitVsHdr), errorAt(single, frame, kLitVsHdr) + 0.01) << "frame " << frame;
}

}  // namespace
}  // namespace probelight
