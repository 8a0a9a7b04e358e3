// The exposure bracket of a recalibration (BracketController), driven frame
// by frame the way the kiosk's processFrame drove its bracket: arrive() for
// every frame first, leadTheLadder() on the recalibration's good frames,
// start() at the fit frame, finish() when arrive() says the bracket is over.
// The camera is a fake with a latency of its own: a ladder asked for while
// frame N is processed shows its first rung in frame N + latency, then one
// rung a frame, the last one held until the next call; an empty call takes
// the frames back to the camera's own exposure after the same latency.
//
// Numbers: the camera's own exposure is 8000 us at gain 2 (16000 us at gain
// 1), so the default ladder (step 3, max 12 stops) is EV -3, -6, -9, -12 =
// 2000, 250, 31.25 and 3.90625 us, all at gain 1, and a frame's EV is
// log2(exposure x gain / 16000).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "capture/exposure_control.hpp"
#include "stages/bracket_controller.hpp"
#include "stages/run_report.hpp"

namespace probelight {
namespace {

constexpr double kTol = 1e-9;
constexpr ManualExposure kOwn{8000.0, 2.0};  // the camera's exposure with AE locked

double gainOf(const FrameExposure& e) { return e.analogue_gain > 0.0 ? e.analogue_gain : 1.0; }
double product(const FrameExposure& e) { return e.exposure_us * gainOf(e); }
// Stops of a frame from an exposure: log2(exposure x gain / base's).
double stopsFrom(const FrameExposure& e, const ManualExposure& base) {
  return std::log2(product(e) / (base.exposure_us * base.analogue_gain));
}

class FakeCamera : public ExposureControl {
 public:
  struct Call {
    std::uint64_t frame = 0;  // asked while this frame was processed
    std::vector<ManualExposure> ladder;
  };

  FakeCamera(int latency, ManualExposure own) : latency_(latency), own_(own) {}

  bool setExposureLadder(const std::vector<ManualExposure>& per_frame) override {
    calls.push_back({now, per_frame});
    if (!controllable) return false;
    requests_.push_back({now + static_cast<std::uint64_t>(latency_), per_frame});
    return true;
  }
  std::optional<double> shortestExposureUs() const override { return reported_shortest_us; }

  // Frame f's metadata: the latest request that has reached it.
  FrameExposure exposureOf(std::uint64_t f) const {
    ManualExposure e = own_;
    for (auto it = requests_.rbegin(); it != requests_.rend(); ++it) {
      if (it->from > f) continue;
      if (!it->ladder.empty()) e = it->ladder[std::min<std::size_t>(f - it->from, it->ladder.size() - 1)];
      break;
    }
    if (sensor_shortest_us) e.exposure_us = std::max(e.exposure_us, *sensor_shortest_us);
    return {e.exposure_us, e.analogue_gain};
  }

  // The camera's AE moved (after a ladder is cleared, frames come back to this).
  void setOwn(ManualExposure own) { own_ = own; }
  // Lost and opened again: a new stream at its own exposure, nothing asked.
  void restart(ManualExposure own) {
    requests_.clear();
    own_ = own;
  }

  std::uint64_t now = 0;  // the frame being processed
  bool controllable = true;
  std::optional<double> reported_shortest_us;  // what shortestExposureUs() says
  std::optional<double> sensor_shortest_us;    // where frames really stop getting shorter
  std::vector<Call> calls;

 private:
  struct Request {
    std::uint64_t from = 0;
    std::vector<ManualExposure> ladder;
  };
  int latency_;
  ManualExposure own_;
  std::vector<Request> requests_;
};

// The kiosk around the controller: the camera, the report, the frame number,
// and the ball, which clips while a frame's exposure x gain is above
// `clips_above` (the room's brightest lamp).
struct Bench {
  explicit Bench(int latency, BracketSettings settings = {}, ManualExposure own = kOwn)
      : camera(latency, own), bracket(settings, camera, report) {}

  FakeCamera camera;
  RunReport report;
  BracketController bracket;
  std::uint64_t frame = 0;
  double clips_above = 1000.0;  // 2000 us (EV -3) clips, 250 us (EV -6) does not
  int clip_questions = 0;

  // Frame n comes from the camera.
  FrameExposure shoot(std::uint64_t n) {
    frame = n;
    camera.now = n;
    return camera.exposureOf(n);
  }
  // Frame n with the metadata given (a scripted sensor).
  FrameExposure shoot(std::uint64_t n, FrameExposure scripted) {
    frame = n;
    camera.now = n;
    return scripted;
  }
  std::function<bool()> clips(FrameExposure e) {
    return [this, e] {
      ++clip_questions;
      return product(e) > clips_above;
    };
  }
  FrameArrival arrive(const FrameExposure& e) { return bracket.arrive(e, frame, clips(e)); }
  void lead(const FrameExposure& e, int good_frames, bool ball_in_view = true, int needed = 5) {
    bracket.leadTheLadder(e, frame, RecalibrationProgress{true, good_frames, needed}, ball_in_view, clips(e));
  }
  BracketStart start(const FrameExposure& e, bool ball_in_view = true) {
    return bracket.start(e, frame, ball_in_view, clips(e));
  }
  long long count(const char* name) const { return report.counter(name); }

  // Frames first, first + 1, ...: good frames from_good .. to_good of a
  // recalibration, each shown (kPipeline) and followed by leadTheLadder.
  void goodFrames(std::uint64_t first, int from_good, int to_good, int needed = 5) {
    for (int good = from_good; good <= to_good; ++good) {
      const FrameExposure e = shoot(first + static_cast<std::uint64_t>(good - from_good));
      ASSERT_EQ(arrive(e).role, FrameRole::kPipeline) << "frame " << frame;
      lead(e, good, true, needed);
    }
  }
};

void expectExposure(const ManualExposure& got, double exposure_us, double gain) {
  EXPECT_NEAR(got.exposure_us, exposure_us, 1e-9 * exposure_us);
  EXPECT_DOUBLE_EQ(got.analogue_gain, gain);
}

void expectEvs(const std::vector<double>& got, const std::vector<double>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_NEAR(got[i], want[i], kTol) << "rung " << i;
}

// The default ladder from kOwn, as the camera is asked for it.
void expectDefaultLadder(const std::vector<ManualExposure>& ladder) {
  ASSERT_EQ(ladder.size(), 4u);
  expectExposure(ladder[0], 2000.0, 1.0);
  expectExposure(ladder[1], 250.0, 1.0);
  expectExposure(ladder[2], 31.25, 1.0);
  expectExposure(ladder[3], 3.90625, 1.0);
}

void expectBracketFrame(const FrameArrival& a, bool keep, double rung_ev, bool over) {
  EXPECT_EQ(a.role, FrameRole::kBracket);
  EXPECT_EQ(a.keep_as_rung, keep);
  if (keep) {
    EXPECT_NEAR(a.rung_ev, rung_ev, kTol);
  }
  EXPECT_EQ(a.bracket_over, over);
  EXPECT_FALSE(a.not_delivered);
}

// ---------------------------------------------------------------------------
// planLadder

TEST(BracketController, PlanLadderStepsDownToMaxStopsWithTheGainAtOne) {
  Bench bench(2);
  const ExposureLadder ladder = bench.bracket.planLadder(kOwn);
  // -3, -6, -9, -12: max_stops 12 is a multiple of 3, so -12 is a rung.
  expectEvs(ladder.ev, {-3.0, -6.0, -9.0, -12.0});
  expectDefaultLadder(ladder.exposures);
  EXPECT_FALSE(ladder.at_shortest);  // the camera says no shortest exposure

  // A step that does not divide max_stops: -5, -10 (-15 is past 12).
  Bench coarse(2, BracketSettings{5.0, 12.0});
  const ExposureLadder two = coarse.bracket.planLadder(kOwn);
  expectEvs(two.ev, {-5.0, -10.0});
  ASSERT_EQ(two.exposures.size(), 2u);
  expectExposure(two.exposures[0], 16000.0 / 32.0, 1.0);
  expectExposure(two.exposures[1], 16000.0 / 1024.0, 1.0);
}

// The gain comes down to 1 first (it adds noise, any sensor takes it), then
// the exposure time: exposure x gain is what the EV is about.
TEST(BracketController, PlanLadderBringsTheGainDownToOneBeforeShorteningTheExposureTime) {
  Bench bench(2);
  const ExposureLadder ladder = bench.bracket.planLadder({10000.0, 4.0});
  // 10000 x 4 = 40000 us at gain 1; EV -3: 5000 us, -6: 625, -9: 78.125, -12: 9.765625.
  expectEvs(ladder.ev, {-3.0, -6.0, -9.0, -12.0});
  ASSERT_EQ(ladder.exposures.size(), 4u);
  expectExposure(ladder.exposures[0], 5000.0, 1.0);
  expectExposure(ladder.exposures[1], 625.0, 1.0);
  expectExposure(ladder.exposures[2], 78.125, 1.0);
  expectExposure(ladder.exposures[3], 9.765625, 1.0);

  // As the original kiosk's exposureAt: every rung is at gain 1, even one
  // whose EV is less than the gain's own stops (gain 8 is 3 stops; EV -1
  // from 1000 us x 8 = 8000 us x 1 is 4000 us at gain 1, not 1000 us at 4).
  Bench fine(2, BracketSettings{1.0, 3.0});
  const ExposureLadder small = fine.bracket.planLadder({1000.0, 8.0});
  expectEvs(small.ev, {-1.0, -2.0, -3.0});
  ASSERT_EQ(small.exposures.size(), 3u);
  expectExposure(small.exposures[0], 4000.0, 1.0);
  expectExposure(small.exposures[1], 2000.0, 1.0);
  expectExposure(small.exposures[2], 1000.0, 1.0);

  // Below gain 1 already: the gain stays (raising it would add noise), only
  // the exposure time comes down. 8000 us at 0.5, EV -3: 1000 us at 0.5.
  const ExposureLadder low = bench.bracket.planLadder({8000.0, 0.5});
  ASSERT_FALSE(low.exposures.empty());
  EXPECT_NEAR(low.ev[0], -3.0, kTol);
  expectExposure(low.exposures[0], 1000.0, 0.5);
}

TEST(BracketController, PlanLadderEndsAtTheSensorsShortestExposureWhereTheCameraSaysIt) {
  {
    // Shortest 100 us: -3 (2000) and -6 (250) are above it; -9 (31.25) is
    // not, and it and everything after become one rung at 100 us, EV
    // log2(100 / 16000) = -7.32, 1.32 stops below -6: kept.
    Bench bench(2);
    bench.camera.reported_shortest_us = 100.0;
    const ExposureLadder ladder = bench.bracket.planLadder(kOwn);
    expectEvs(ladder.ev, {-3.0, -6.0, std::log2(100.0 / 16000.0)});
    ASSERT_EQ(ladder.exposures.size(), 3u);
    expectExposure(ladder.exposures[2], 100.0, 1.0);
    EXPECT_TRUE(ladder.at_shortest);
  }
  {
    // Shortest 200 us: that rung would be log2(200 / 16000) = -6.32, only
    // 0.32 stops below -6 (less than kNewRungStops): left out. The ladder
    // still ends at the shortest exposure (250 us is as far as it goes).
    Bench bench(2);
    bench.camera.reported_shortest_us = 200.0;
    const ExposureLadder ladder = bench.bracket.planLadder(kOwn);
    expectEvs(ladder.ev, {-3.0, -6.0});
    ASSERT_EQ(ladder.exposures.size(), 2u);
    expectExposure(ladder.exposures[1], 250.0, 1.0);
    EXPECT_TRUE(ladder.at_shortest);
  }
  {
    // Shortest exactly the first rung: -3 is not below it (kept); -6 becomes
    // 2000 us again, no shorter than -3: left out.
    Bench bench(2);
    bench.camera.reported_shortest_us = 2000.0;
    const ExposureLadder ladder = bench.bracket.planLadder(kOwn);
    expectEvs(ladder.ev, {-3.0});
    EXPECT_TRUE(ladder.at_shortest);
  }
  {
    // Already at the shortest (100 us at gain 1): nothing shorter to ask for.
    Bench bench(2);
    bench.camera.reported_shortest_us = 100.0;
    const ExposureLadder ladder = bench.bracket.planLadder({100.0, 1.0});
    EXPECT_TRUE(ladder.ev.empty());
    EXPECT_TRUE(ladder.exposures.empty());
    EXPECT_TRUE(ladder.at_shortest);
  }
  {
    // At the shortest exposure time but at gain 4: the gain can still come
    // down, 2 stops (100 us at gain 1, EV log2(100 / 400) = -2).
    Bench bench(2);
    bench.camera.reported_shortest_us = 100.0;
    const ExposureLadder ladder = bench.bracket.planLadder({100.0, 4.0});
    expectEvs(ladder.ev, {-2.0});
    ASSERT_EQ(ladder.exposures.size(), 1u);
    expectExposure(ladder.exposures[0], 100.0, 1.0);
    EXPECT_TRUE(ladder.at_shortest);
  }
}

// ---------------------------------------------------------------------------
// The early ladder and the camera's latency

// Latency 2, as quick as the initial lead: the ladder asked at good frame 3
// (5 - 2) shows its first rung in the frame that would have been the fit's.
TEST(BracketController, AQuickCameraCallsTheEarlyLadderOffAndTheFitAsksForItsOwn) {
  Bench bench(2);
  EXPECT_EQ(bench.bracket.leadFrames(), BracketController::kInitialLeadFrames);
  // Frames 10-12: good frames 1-3. Nothing is asked at 1 and 2; at 3 (5 - the
  // lead of 2) the ball clips at the normal exposure: the whole ladder,
  // planned from frame 12's exposure, goes out.
  bench.goodFrames(10, 1, 2);
  EXPECT_TRUE(bench.camera.calls.empty());
  bench.goodFrames(12, 3, 3);
  EXPECT_TRUE(bench.bracket.earlyLadderOut());
  EXPECT_EQ(bench.count("bracket_early_ladders"), 1);
  ASSERT_EQ(bench.camera.calls.size(), 1u);
  EXPECT_EQ(bench.camera.calls[0].frame, 12u);
  expectDefaultLadder(bench.camera.calls[0].ladder);

  // Frame 13: still at the normal exposure (the ladder shows from 14): good
  // frame 4, and the ladder stays out (4 >= 5 - 2).
  bench.goodFrames(13, 4, 4);
  EXPECT_TRUE(bench.bracket.earlyLadderOut());
  EXPECT_EQ(bench.camera.calls.size(), 1u);

  // Frame 14, which would have been the fit frame: its metadata is already
  // the first rung (EV -3). Darker than the fit's frame should be: the early
  // ladder is called off (the camera is told to go back), the frame is not
  // shown (settling: it is 3 stops from the early ladder's base), and the
  // lead becomes 0 (the camera is quicker than any lead).
  FrameExposure e = bench.shoot(14);
  ASSERT_NEAR(stopsFrom(e, kOwn), -3.0, kTol);  // the fake camera's latency
  FrameArrival a = bench.arrive(e);
  EXPECT_EQ(a.role, FrameRole::kSettling);
  EXPECT_FALSE(a.keep_as_rung);
  EXPECT_FALSE(a.bracket_over);
  EXPECT_EQ(bench.count("bracket_early_ladders_too_early"), 1);
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 0);
  EXPECT_FALSE(bench.bracket.earlyLadderOut());
  EXPECT_TRUE(bench.bracket.settling());
  EXPECT_FALSE(bench.bracket.pending());
  EXPECT_EQ(bench.bracket.leadFrames(), 0);
  ASSERT_EQ(bench.camera.calls.size(), 2u);
  EXPECT_EQ(bench.camera.calls[1].frame, 14u);
  EXPECT_TRUE(bench.camera.calls[1].ladder.empty());

  // Frame 15: the second rung (EV -6), in flight before the call-off: not
  // shown either.
  e = bench.shoot(15);
  ASSERT_NEAR(stopsFrom(e, kOwn), -6.0, kTol);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kSettling);

  // Frame 16: back at the normal exposure (the call-off took the same 2
  // frames): shown, and it is good frame 5: the fit. (The called-off
  // ladder's window is still open: a later rung of it would be held back.)
  // No early ladder is out, so the fit asks for the whole ladder itself.
  e = bench.shoot(16);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  EXPECT_TRUE(bench.bracket.settling());
  EXPECT_EQ(bench.start(e), BracketStart::kStarted);
  EXPECT_TRUE(bench.bracket.pending());
  EXPECT_EQ(bench.count("brackets_started"), 1);
  ASSERT_EQ(bench.camera.calls.size(), 3u);
  EXPECT_EQ(bench.camera.calls[2].frame, 16u);
  expectDefaultLadder(bench.camera.calls[2].ladder);

  // Frame 17: in flight before the ask (normal exposure): a bracket frame,
  // waited for. Frame 18: EV -3, the ball still clips: kept, go on.
  // Frame 19: EV -6, the ball no longer clips: kept, and the bracket is over.
  expectBracketFrame(bench.arrive(bench.shoot(17)), false, 0.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(18)), true, -3.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(19)), true, -6.0, true);
  const BracketRecord record = bench.bracket.finish();
  EXPECT_FALSE(bench.bracket.pending());
  EXPECT_EQ(record.started_frame, 16u);
  EXPECT_EQ(record.lead_frames, 0);     // asked at the fit frame itself
  EXPECT_EQ(record.latency_frames, 2);  // asked at 16, first rung at 18
  expectEvs(record.rung_ev, {-3.0, -6.0});
  expectEvs(record.ladder.ev, {-3.0, -6.0, -9.0, -12.0});
  EXPECT_EQ(bench.bracket.leadFrames(), 1);  // latency 2, less one
  EXPECT_EQ(bench.count("bracket_frames"), 2);
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 0);

  // The next recalibration leads by 1: asked at good frame 4 (frame 33), the
  // first rung comes right after the fit (34 + 1 = 33 + 2), none too early.
  bench.goodFrames(30, 1, 4);
  ASSERT_EQ(bench.camera.calls.size(), 5u);  // 19's clear, 33's ladder
  EXPECT_EQ(bench.camera.calls[4].frame, 33u);
  e = bench.shoot(34);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  EXPECT_EQ(bench.start(e), BracketStart::kStarted);
  EXPECT_EQ(bench.camera.calls.size(), 5u);  // the early ladder adopted: nothing asked again
  expectBracketFrame(bench.arrive(bench.shoot(35)), true, -3.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(36)), true, -6.0, true);
  const BracketRecord second = bench.bracket.finish();
  EXPECT_EQ(second.lead_frames, 1);
  EXPECT_EQ(second.latency_frames, 2);
  EXPECT_EQ(bench.bracket.leadFrames(), 1);
  EXPECT_EQ(bench.count("bracket_early_ladders"), 2);
  EXPECT_EQ(bench.count("bracket_early_ladders_too_early"), 1);
}

// Latency 1: the early rung shows a good frame before the fit's, and the
// lead learnt is 0: later recalibrations ask nothing early.
TEST(BracketController, AVeryQuickCameraLeadsByNothing) {
  Bench bench(1);
  bench.goodFrames(10, 1, 3);  // asked at frame 12
  ASSERT_EQ(bench.camera.calls.size(), 1u);
  // Frame 13, which would have been good frame 4: the first rung already.
  // Called off, not shown, the lead 0.
  FrameExposure e = bench.shoot(13);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kSettling);
  EXPECT_EQ(bench.count("bracket_early_ladders_too_early"), 1);
  EXPECT_EQ(bench.bracket.leadFrames(), 0);
  // Frame 14: back (the call-off at 13 showed after 1 frame): good frame 4.
  // With a lead of 0 nothing is asked early.
  bench.goodFrames(14, 4, 4);
  EXPECT_EQ(bench.camera.calls.size(), 2u);  // 12's ladder, 13's clear
  EXPECT_FALSE(bench.bracket.earlyLadderOut());
  // Frame 15: the fit asks; frame 16 is its first rung.
  e = bench.shoot(15);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  EXPECT_EQ(bench.start(e), BracketStart::kStarted);
  ASSERT_EQ(bench.camera.calls.size(), 3u);
  EXPECT_EQ(bench.camera.calls[2].frame, 15u);
  expectBracketFrame(bench.arrive(bench.shoot(16)), true, -3.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(17)), true, -6.0, true);
  const BracketRecord record = bench.bracket.finish();
  EXPECT_EQ(record.lead_frames, 0);
  EXPECT_EQ(record.latency_frames, 1);
  EXPECT_EQ(bench.bracket.leadFrames(), 0);  // 1 - 1
  // A later recalibration: no good frame asks for anything.
  bench.goodFrames(30, 1, 4);
  EXPECT_EQ(bench.camera.calls.size(), 4u);  // + 17's clear only
  EXPECT_EQ(bench.count("bracket_early_ladders"), 1);
}

// Latency 4: slower than the lead. The ladder asked 2 frames before the fit
// frame shows 2 frames after it; the bracket ends at the first rung whose
// ball no longer clips, and the next recalibration leads by 3.
TEST(BracketController, ASlowCamerasRungsFollowTheFitAndTheBracketEndsWhenTheBallStopsClipping) {
  Bench bench(4);
  bench.goodFrames(10, 1, 4);  // frame 12 (good frame 3) asks for the ladder
  ASSERT_EQ(bench.camera.calls.size(), 1u);
  EXPECT_EQ(bench.camera.calls[0].frame, 12u);
  EXPECT_TRUE(bench.bracket.earlyLadderOut());

  // Frame 14: good frame 5, still at the normal exposure (nothing before 16
  // shows the ladder): shown, and the fit. The early ladder is adopted: its
  // rungs are on their way, nothing is asked again.
  FrameExposure e = bench.shoot(14);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  EXPECT_EQ(bench.start(e), BracketStart::kStarted);
  EXPECT_EQ(bench.camera.calls.size(), 1u);
  EXPECT_FALSE(bench.bracket.earlyLadderOut());
  EXPECT_TRUE(bench.bracket.pending());
  EXPECT_EQ(bench.count("brackets_started"), 1);
  EXPECT_EQ(bench.count("bracket_early_ladders_too_early"), 0);

  // Frame 15: in flight at the normal exposure: a bracket frame, not a rung,
  // and the ball is not looked at (only rungs are).
  const int questions = bench.clip_questions;
  expectBracketFrame(bench.arrive(bench.shoot(15)), false, 0.0, false);
  EXPECT_EQ(bench.clip_questions, questions);
  // Frame 16: EV -3, the ball still clips (2000 > 1000): kept.
  expectBracketFrame(bench.arrive(bench.shoot(16)), true, -3.0, false);
  // Frame 17: EV -6, the ball no longer clips (250 < 1000): kept and over,
  // though the ladder goes on to -12.
  expectBracketFrame(bench.arrive(bench.shoot(17)), true, -6.0, true);
  EXPECT_EQ(bench.clip_questions, questions + 2);
  EXPECT_TRUE(bench.bracket.pending());  // until finish()
  const BracketRecord record = bench.bracket.finish();
  EXPECT_FALSE(bench.bracket.pending());
  // The rest of the ladder is dropped: the camera is told to go back.
  ASSERT_EQ(bench.camera.calls.size(), 2u);
  EXPECT_EQ(bench.camera.calls[1].frame, 17u);
  EXPECT_TRUE(bench.camera.calls[1].ladder.empty());
  // The record: what was asked, from what, when, and what was kept.
  expectEvs(record.ladder.ev, {-3.0, -6.0, -9.0, -12.0});
  expectDefaultLadder(record.ladder.exposures);
  EXPECT_FALSE(record.ladder.at_shortest);
  expectExposure(record.base, 8000.0, 2.0);
  EXPECT_EQ(record.started_frame, 14u);
  EXPECT_EQ(record.lead_frames, 2);     // asked at 12, fit at 14
  EXPECT_EQ(record.latency_frames, 4);  // asked at 12, first rung at 16: the camera's
  expectEvs(record.rung_ev, {-3.0, -6.0});
  EXPECT_EQ(bench.bracket.leadFrames(), 3);  // 4 - 1
  EXPECT_EQ(bench.count("bracket_frames"), 2);
  EXPECT_EQ(bench.count("bracket_exposures_clamped"), 0);
  EXPECT_EQ(bench.count("bracket_exposures_not_delivered"), 0);
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 0);

  // Frames 18-20 were asked before the clear: EV -9, -12, -12 (held). Not
  // shown: settling, more than kEvMatchStops from the normal exposure.
  EXPECT_TRUE(bench.bracket.settling());
  for (std::uint64_t f = 18; f <= 20; ++f) {
    e = bench.shoot(f);
    ASSERT_LT(stopsFrom(e, kOwn), -8.0);
    EXPECT_EQ(bench.arrive(e).role, FrameRole::kSettling) << "frame " << f;
  }
  // Frame 21: the clear at 17 has reached it: back, shown.
  e = bench.shoot(21);
  ASSERT_NEAR(stopsFrom(e, kOwn), 0.0, kTol);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  EXPECT_FALSE(bench.bracket.settling());

  // The next recalibration leads by 3: asked at good frame 2 (frame 31),
  // the fit at 34, the first rung at 35 (31 + 4), right after it.
  bench.goodFrames(30, 1, 1);
  EXPECT_EQ(bench.camera.calls.size(), 2u);
  bench.goodFrames(31, 2, 4);
  ASSERT_EQ(bench.camera.calls.size(), 3u);
  EXPECT_EQ(bench.camera.calls[2].frame, 31u);
  e = bench.shoot(34);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  EXPECT_EQ(bench.start(e), BracketStart::kStarted);
  expectBracketFrame(bench.arrive(bench.shoot(35)), true, -3.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(36)), true, -6.0, true);
  const BracketRecord second = bench.bracket.finish();
  EXPECT_EQ(second.lead_frames, 3);
  EXPECT_EQ(second.latency_frames, 4);  // (35 - 34) + 3
  EXPECT_EQ(bench.bracket.leadFrames(), 3);
}

// Whatever the camera's latency, the record says it and the lead becomes
// it less one, at most kMaxLeadFrames.
class BracketControllerLatency : public ::testing::TestWithParam<int> {};

TEST_P(BracketControllerLatency, TheFirstRungSaysTheLatencyAndTheLeadFollows) {
  const int latency = GetParam();
  Bench bench(latency);
  bench.goodFrames(10, 1, 4);  // asked at 12 (lead 2)
  FrameExposure e = bench.shoot(14);
  ASSERT_EQ(bench.arrive(e).role, FrameRole::kPipeline);  // 14 < 12 + latency
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  const std::uint64_t first_rung = 12 + static_cast<std::uint64_t>(latency);
  for (std::uint64_t f = 15; f < first_rung; ++f) expectBracketFrame(bench.arrive(bench.shoot(f)), false, 0.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(first_rung)), true, -3.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(first_rung + 1)), true, -6.0, true);
  const BracketRecord record = bench.bracket.finish();
  EXPECT_EQ(record.lead_frames, 2);
  EXPECT_EQ(record.latency_frames, latency);
  EXPECT_EQ(bench.bracket.leadFrames(), std::clamp(latency - 1, 0, BracketController::kMaxLeadFrames));
}

// 9: the first rung 7 frames after the fit (within kMaxWaitFrames); lead 8
// clamped to 6.
INSTANTIATE_TEST_SUITE_P(BracketControllerSlowCameras, BracketControllerLatency, ::testing::Values(3, 4, 5, 9));

// A lead longer than the recalibration's good frames asks at the first good
// frame (needed - 1 frames before the fit), never before the count began.
TEST(BracketController, TheLeadReachesBackNoFurtherThanTheFirstGoodFrame) {
  Bench bench(9);
  bench.goodFrames(10, 1, 4);
  FrameExposure e = bench.shoot(14);
  bench.arrive(e);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  for (std::uint64_t f = 15; f <= 22; ++f) bench.arrive(bench.shoot(f));  // first rung at 21, over at 22
  ASSERT_FALSE(bench.bracket.finish().rung_ev.empty());
  ASSERT_EQ(bench.bracket.leadFrames(), BracketController::kMaxLeadFrames);
  // Settled long after; a new recalibration of 5 good frames: lead min(6, 4).
  const std::size_t calls = bench.camera.calls.size();
  bench.goodFrames(40, 1, 1);
  ASSERT_EQ(bench.camera.calls.size(), calls + 1);
  EXPECT_EQ(bench.camera.calls.back().frame, 40u);
  EXPECT_TRUE(bench.bracket.earlyLadderOut());
  bench.goodFrames(41, 2, 4);  // kept out through good frames 2-4
  EXPECT_EQ(bench.camera.calls.size(), calls + 1);
  e = bench.shoot(44);
  bench.arrive(e);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  EXPECT_TRUE(bench.bracket.pending());
  for (std::uint64_t f = 45; f <= 50; ++f) bench.arrive(bench.shoot(f));  // first rung at 49, over at 50
  EXPECT_EQ(bench.bracket.finish().lead_frames, 4);
}

// The count starts over (the ball was lost) while an early ladder is out:
// called off, and the frames it still has in flight are not shown.
TEST(BracketController, ARecalibrationThatStartsOverCallsTheEarlyLadderOff) {
  Bench bench(2);
  bench.goodFrames(10, 1, 3);  // asked at 12; it would show from 14
  ASSERT_TRUE(bench.bracket.earlyLadderOut());
  // Frame 13: the ball is not seen: the count is back to 0.
  FrameExposure e = bench.shoot(13);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  bench.lead(e, 0, false);
  EXPECT_FALSE(bench.bracket.earlyLadderOut());
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 1);
  EXPECT_EQ(bench.count("bracket_early_ladders_too_early"), 0);
  ASSERT_EQ(bench.camera.calls.size(), 2u);
  EXPECT_EQ(bench.camera.calls[1].frame, 13u);
  EXPECT_TRUE(bench.camera.calls[1].ladder.empty());
  EXPECT_TRUE(bench.bracket.settling());  // as the original's cancelEarlyLadder
  // Frame 14: the first rung, in flight before the call-off: not shown, and
  // not "too early" (no early ladder is out any more).
  e = bench.shoot(14);
  ASSERT_NEAR(stopsFrom(e, kOwn), -3.0, kTol);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kSettling);
  EXPECT_EQ(bench.count("bracket_early_ladders_too_early"), 0);
  EXPECT_EQ(bench.bracket.leadFrames(), BracketController::kInitialLeadFrames);
  // Frame 15: back: shown. The count begins again (good frame 1): nothing
  // more to call off, nothing asked.
  bench.goodFrames(15, 1, 2);
  EXPECT_EQ(bench.camera.calls.size(), 2u);
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 1);
  // At good frame 3 again (frame 17): asked again.
  bench.goodFrames(17, 3, 3);
  EXPECT_EQ(bench.camera.calls.size(), 3u);
  EXPECT_EQ(bench.count("bracket_early_ladders"), 2);
}

// A slower camera: the ladder called off before its first rung came. Frames
// at the normal exposure come first and are shown, then the rungs already
// begun arrive anyway: each is held back (it would show a dark room, and
// the maps would be made from it), until the call-off reaches the sensor.
TEST(BracketController, RungsStillInFlightAfterACallOffAreHeldBackBehindNormalFrames) {
  Bench bench(4);
  bench.goodFrames(10, 1, 3);  // asked at 12; its rungs would show from 16
  ASSERT_TRUE(bench.bracket.earlyLadderOut());
  // Frame 13: the ball is lost, the count starts over: called off (the
  // empty call reaches the sensor at 17).
  FrameExposure e = bench.shoot(13);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  bench.lead(e, 0, false);
  ASSERT_FALSE(bench.bracket.earlyLadderOut());
  // Frames 14, 15: the normal exposure: shown.
  for (const std::uint64_t n : {14u, 15u}) {
    e = bench.shoot(n);
    ASSERT_NEAR(stopsFrom(e, kOwn), 0.0, kTol);
    EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline) << "frame " << n;
  }
  // Frame 16: the first rung, begun before the call-off: held back.
  e = bench.shoot(16);
  ASSERT_NEAR(stopsFrom(e, kOwn), -3.0, kTol);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kSettling);
  // Frame 17 onwards: back at the normal exposure, shown; and after the
  // window a later darker frame (the room's own change) is not held.
  for (std::uint64_t n = 17; n <= 22; ++n) {
    e = bench.shoot(n);
    ASSERT_NEAR(stopsFrom(e, kOwn), 0.0, kTol) << "frame " << n;
    EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline) << "frame " << n;
  }
  EXPECT_FALSE(bench.bracket.settling()) << "eight frames after the call-off, nothing of its ladder can come";
  e = bench.shoot(23, FrameExposure{4000.0, 2.0});  // AE shortened by two stops
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
}

// A fit that takes no bracket calls an early ladder off through
// fitWithoutBracket(): the ball not in view at the fit, the ball no longer
// clipping there, or the recalibration giving up.
TEST(BracketController, AFitWithoutABracketCallsTheEarlyLadderOff) {
  Bench bench(3);
  bench.goodFrames(10, 1, 4);  // asked at 12, it would show from 15
  FrameExposure e = bench.shoot(14);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  // The tag was lost at the fit frame: no outline, no bracket (and nothing
  // counted for it: the fit goes on).
  EXPECT_EQ(bench.start(e, false), BracketStart::kBallNotInView);
  EXPECT_FALSE(bench.bracket.pending());
  bench.bracket.fitWithoutBracket();
  EXPECT_FALSE(bench.bracket.earlyLadderOut());
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 1);
  EXPECT_EQ(bench.count("brackets_started"), 0);
  EXPECT_EQ(bench.count("brackets_not_needed"), 0);
  ASSERT_EQ(bench.camera.calls.size(), 2u);
  EXPECT_EQ(bench.camera.calls[1].frame, 14u);
  EXPECT_TRUE(bench.camera.calls[1].ladder.empty());
  // Frames 15 and 16 were asked before the call-off (EV -3, -6): not shown.
  // Frame 17 is back.
  EXPECT_EQ(bench.arrive(bench.shoot(15)).role, FrameRole::kSettling);
  EXPECT_EQ(bench.arrive(bench.shoot(16)).role, FrameRole::kSettling);
  EXPECT_EQ(bench.arrive(bench.shoot(17)).role, FrameRole::kPipeline);

  // The next recalibration: asked at 32; at the fit (34) the lamp that
  // clipped is off (nothing clips any more): not needed, called off.
  bench.goodFrames(30, 1, 4);
  ASSERT_EQ(bench.camera.calls.size(), 3u);
  e = bench.shoot(34);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  bench.clips_above = 1e12;
  EXPECT_EQ(bench.start(e), BracketStart::kNotNeeded);
  EXPECT_EQ(bench.count("brackets_not_needed"), 1);
  bench.bracket.fitWithoutBracket();
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 2);
  ASSERT_EQ(bench.camera.calls.size(), 4u);
  EXPECT_TRUE(bench.camera.calls[3].ladder.empty());

  // A recalibration that gives up with a ladder out (the ball lit, then the
  // tag lost for good until max_frames): called off the same way.
  bench.clips_above = 1000.0;
  bench.goodFrames(50, 1, 3);  // asked at 52
  ASSERT_EQ(bench.camera.calls.size(), 5u);
  bench.bracket.fitWithoutBracket();
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 3);
  EXPECT_EQ(bench.camera.calls.size(), 6u);
  // With nothing out, fitWithoutBracket() has nothing to do.
  bench.bracket.fitWithoutBracket();
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 3);
  EXPECT_EQ(bench.camera.calls.size(), 6u);
  EXPECT_EQ(bench.count("bracket_early_ladders"), 3);
}

// The fit frame's exposure is the base of the rungs' EVs, also when the
// early ladder was planned from another one (AE not locked, it moved up a
// stop between the ask and the fit). Scripted frames: the camera only
// records what is asked.
TEST(BracketController, AnAdoptedLadderIsReckonedFromTheFitFramesExposure) {
  Bench bench(2);
  for (int good = 1; good <= 3; ++good) {
    const FrameExposure e = bench.shoot(9 + good, {8000.0, 2.0});
    ASSERT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
    bench.lead(e, good);
  }
  ASSERT_EQ(bench.camera.calls.size(), 1u);  // planned from 8000 x 2
  expectDefaultLadder(bench.camera.calls[0].ladder);
  // Frame 13: a stop brighter (not darker: no rung, not too early).
  FrameExposure e = bench.shoot(13, {16000.0, 2.0});
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  bench.lead(e, 4);
  EXPECT_TRUE(bench.bracket.earlyLadderOut());
  // Frame 14, the fit, at 16000 x 2 = 32000: the rungs asked (2000 us ...)
  // are EV -4, -7, -10, -13 from it.
  e = bench.shoot(14, {16000.0, 2.0});
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  EXPECT_EQ(bench.camera.calls.size(), 1u);
  expectBracketFrame(bench.arrive(bench.shoot(15, {2000.0, 1.0})), true, -4.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(16, {250.0, 1.0})), true, -7.0, true);
  const BracketRecord record = bench.bracket.finish();
  expectExposure(record.base, 16000.0, 2.0);
  expectEvs(record.ladder.ev, {-4.0, -7.0, -10.0, -13.0});
  expectDefaultLadder(record.ladder.exposures);  // the exposures asked are unchanged
  expectEvs(record.rung_ev, {-4.0, -7.0});
  EXPECT_EQ(record.lead_frames, 2);
  EXPECT_EQ(record.latency_frames, 3);  // (15 - 14) + 2
}

// Too early is any frame darker than the early ladder's base by more than
// kEvMatchStops (a sensor that applies the gain of the first rung a frame
// before its exposure time, say), not only a whole rung. Scripted frames.
TEST(BracketController, AFrameAQuarterStopDarkerThanTheEarlyBaseIsTooEarly) {
  Bench bench(2);
  for (int good = 1; good <= 3; ++good) {
    const FrameExposure e = bench.shoot(9 + good, {8000.0, 2.0});
    ASSERT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
    bench.lead(e, good);
  }
  ASSERT_TRUE(bench.bracket.earlyLadderOut());
  // 7000 x 2: log2(7000 / 8000) = -0.19 stops: within kEvMatchStops, shown.
  FrameExposure e = bench.shoot(13, {7000.0, 2.0});
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  bench.lead(e, 4);
  EXPECT_TRUE(bench.bracket.earlyLadderOut());
  // 6400 x 2: log2(0.8) = -0.32 stops: too early, not shown.
  e = bench.shoot(14, {6400.0, 2.0});
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kSettling);
  EXPECT_FALSE(bench.bracket.earlyLadderOut());
  EXPECT_EQ(bench.count("bracket_early_ladders_too_early"), 1);
  EXPECT_EQ(bench.bracket.leadFrames(), 0);
}

// ---------------------------------------------------------------------------
// Losing the camera

// Lost mid-bracket: the bracket stays pending (the kiosk finishes it with
// what it has), and the new stream's frames are held until one is back at
// the bracket's base (the original: cameraLost reset the settling, then
// whileCameraLost's finishBracket set it to the base).
TEST(BracketController, ACameraLostMidBracketStaysPendingUntilFinishAndTheNewStreamSettlesOnItsBase) {
  Bench bench(3);
  bench.clips_above = 100.0;  // clips at -3 (2000) and -6 (250), not at -9 (31.25)
  bench.goodFrames(10, 1, 4);  // asked at 12
  FrameExposure e = bench.shoot(14);
  bench.arrive(e);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  expectBracketFrame(bench.arrive(bench.shoot(15)), true, -3.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(16)), true, -6.0, false);
  // The camera is lost before frame 17 (counted as the original's cameraLost did).
  bench.bracket.onCameraLost();
  EXPECT_TRUE(bench.bracket.pending());
  EXPECT_EQ(bench.count("brackets_cut_by_camera_loss"), 1);
  EXPECT_FALSE(bench.bracket.settling());
  EXPECT_FALSE(bench.bracket.earlyLadderOut());
  const BracketRecord record = bench.bracket.finish();
  EXPECT_FALSE(bench.bracket.pending());
  expectEvs(record.rung_ev, {-3.0, -6.0});  // what it had
  expectEvs(record.ladder.ev, {-3.0, -6.0, -9.0, -12.0});
  expectExposure(record.base, 8000.0, 2.0);
  EXPECT_EQ(record.started_frame, 14u);
  EXPECT_EQ(record.latency_frames, 3);
  EXPECT_EQ(bench.bracket.leadFrames(), 2);
  EXPECT_EQ(bench.count("bracket_frames"), 2);
  ASSERT_FALSE(bench.camera.calls.empty());
  EXPECT_TRUE(bench.camera.calls.back().ladder.empty());  // the camera goes back
  EXPECT_TRUE(bench.bracket.settling());                  // ... to the bracket's base

  // The camera is back; its new stream starts with AE 2 stops above the
  // base: held (kSettling), compared with the bracket's base...
  bench.camera.restart({32000.0, 2.0});
  for (std::uint64_t f = 17; f <= 18; ++f) {
    e = bench.shoot(f);
    ASSERT_NEAR(stopsFrom(e, kOwn), 2.0, kTol);
    EXPECT_EQ(bench.arrive(e).role, FrameRole::kSettling) << "frame " << f;
  }
  // ... until a frame is within kEvMatchStops of it (8800 x 2: 0.14 stops).
  bench.camera.setOwn({8800.0, 2.0});
  e = bench.shoot(19);
  ASSERT_LT(std::abs(stopsFrom(e, kOwn)), BracketController::kEvMatchStops);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  EXPECT_FALSE(bench.bracket.settling());
}

// Lost before a bracket: an early ladder out and the settling after a
// bracket belong to the old stream, and are dropped (not counted as
// unused: the original's cameraLost reset them).
TEST(BracketController, ACameraLossDropsTheEarlyLadderAndTheSettling) {
  Bench bench(4);
  bench.goodFrames(10, 1, 4);  // asked at 12
  ASSERT_TRUE(bench.bracket.earlyLadderOut());
  bench.bracket.onCameraLost();
  EXPECT_FALSE(bench.bracket.earlyLadderOut());
  EXPECT_FALSE(bench.bracket.settling());
  EXPECT_FALSE(bench.bracket.pending());
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 0);
  EXPECT_EQ(bench.count("bracket_early_ladders_too_early"), 0);
  EXPECT_EQ(bench.count("brackets_cut_by_camera_loss"), 0);  // no bracket was being taken
  const std::size_t calls = bench.camera.calls.size();

  // Back (the recalibration goes on where it was): good frame 4 again asks
  // nothing (the lead's frame was 3), and the fit asks for its own ladder.
  bench.camera.restart(kOwn);
  bench.goodFrames(20, 4, 4);
  EXPECT_EQ(bench.camera.calls.size(), calls);
  FrameExposure e = bench.shoot(21);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  ASSERT_EQ(bench.camera.calls.size(), calls + 1);
  EXPECT_EQ(bench.camera.calls.back().frame, 21u);
  expectDefaultLadder(bench.camera.calls.back().ladder);
  for (std::uint64_t f = 22; f <= 24; ++f) expectBracketFrame(bench.arrive(bench.shoot(f)), false, 0.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(25)), true, -3.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(26)), true, -6.0, true);
  const BracketRecord record = bench.bracket.finish();
  EXPECT_EQ(record.lead_frames, 0);
  EXPECT_EQ(record.latency_frames, 4);
  // Frame 27 is still at EV -9: settling.
  EXPECT_EQ(bench.arrive(bench.shoot(27)).role, FrameRole::kSettling);
  ASSERT_TRUE(bench.bracket.settling());

  // Lost again: the settling goes with the old stream. The new one starts 2
  // stops above the base and is shown at once.
  bench.bracket.onCameraLost();
  EXPECT_FALSE(bench.bracket.settling());
  bench.camera.restart({32000.0, 2.0});
  EXPECT_EQ(bench.arrive(bench.shoot(30)).role, FrameRole::kPipeline);
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 0);
  EXPECT_EQ(bench.count("brackets_cut_by_camera_loss"), 0);
}

// ---------------------------------------------------------------------------
// Presses during a bracket

// The kiosk ignores presses (and long presses) while a bracket is pending:
// "a bracket still being taken is part of the recalibration before it". The
// controller's side of that is pending(): true from start() through every
// bracket frame, the last one included, until finish().
TEST(BracketController, PendingFromStartThroughEveryBracketFrameUntilFinish) {
  Bench bench(4);
  bench.clips_above = 100.0;  // over at -9
  for (int good = 1; good <= 4; ++good) {
    const FrameExposure e = bench.shoot(9 + good);
    bench.arrive(e);
    bench.lead(e, good);
    EXPECT_FALSE(bench.bracket.pending()) << "good frame " << good;
  }
  FrameExposure e = bench.shoot(14);
  bench.arrive(e);
  EXPECT_FALSE(bench.bracket.pending());
  EXPECT_EQ(bench.bracket.pendingLadder(), nullptr);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  EXPECT_TRUE(bench.bracket.pending());
  ASSERT_NE(bench.bracket.pendingLadder(), nullptr);
  expectEvs(bench.bracket.pendingLadder()->ev, {-3.0, -6.0, -9.0, -12.0});
  expectBracketFrame(bench.arrive(bench.shoot(15)), false, 0.0, false);
  EXPECT_TRUE(bench.bracket.pending());
  expectBracketFrame(bench.arrive(bench.shoot(16)), true, -3.0, false);
  EXPECT_TRUE(bench.bracket.pending());
  expectBracketFrame(bench.arrive(bench.shoot(17)), true, -6.0, false);
  EXPECT_TRUE(bench.bracket.pending());
  expectBracketFrame(bench.arrive(bench.shoot(18)), true, -9.0, true);
  EXPECT_TRUE(bench.bracket.pending());  // over, not finished: a press now is still ignored
  const BracketRecord record = bench.bracket.finish();
  EXPECT_FALSE(bench.bracket.pending());  // a press now is taken
  EXPECT_EQ(bench.bracket.pendingLadder(), nullptr);
  expectEvs(record.rung_ev, {-3.0, -6.0, -9.0});
  // Frames settling after it are no bracket: pending() stays false.
  e = bench.shoot(19);
  EXPECT_EQ(bench.arrive(e).role, FrameRole::kSettling);
  EXPECT_FALSE(bench.bracket.pending());
}

// Were a press taken during a bracket, it would start a recalibration that
// counts good frames from 0 and calls leadTheLadder with them. Whatever
// count it reached, that must not touch the pending bracket: nothing asked
// of the camera (its rungs are on their way), no early ladder, and the
// bracket goes on and ends as it would have.
TEST(BracketController, ALeadAskedDuringAPendingBracketLeavesItsRungsAlone) {
  Bench bench(4);
  bench.clips_above = 100.0;  // over at -9
  bench.goodFrames(10, 1, 4);  // asked at 12
  FrameExposure e = bench.shoot(14);
  bench.arrive(e);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  const std::size_t calls = bench.camera.calls.size();
  const auto pressedRecalibration = [&](const FrameExposure& frame) {
    for (int good = 0; good <= 4; ++good) bench.lead(frame, good);
    EXPECT_EQ(bench.camera.calls.size(), calls) << "frame " << bench.frame;
    EXPECT_FALSE(bench.bracket.earlyLadderOut()) << "frame " << bench.frame;
    EXPECT_TRUE(bench.bracket.pending()) << "frame " << bench.frame;
    ASSERT_NE(bench.bracket.pendingLadder(), nullptr);
    expectEvs(bench.bracket.pendingLadder()->ev, {-3.0, -6.0, -9.0, -12.0});
    expectDefaultLadder(bench.bracket.pendingLadder()->exposures);
  };
  e = bench.shoot(15);  // in flight, at the normal exposure: the ball clips in it
  expectBracketFrame(bench.arrive(e), false, 0.0, false);
  pressedRecalibration(e);
  e = bench.shoot(16);
  expectBracketFrame(bench.arrive(e), true, -3.0, false);
  pressedRecalibration(e);
  e = bench.shoot(17);
  expectBracketFrame(bench.arrive(e), true, -6.0, false);
  pressedRecalibration(e);
  expectBracketFrame(bench.arrive(bench.shoot(18)), true, -9.0, true);
  const BracketRecord record = bench.bracket.finish();
  expectEvs(record.ladder.ev, {-3.0, -6.0, -9.0, -12.0});
  expectEvs(record.rung_ev, {-3.0, -6.0, -9.0});
  expectExposure(record.base, 8000.0, 2.0);
  EXPECT_EQ(record.started_frame, 14u);
  EXPECT_EQ(record.lead_frames, 2);
  EXPECT_EQ(record.latency_frames, 4);
  EXPECT_EQ(bench.count("bracket_early_ladders"), 1);
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 0);
  EXPECT_EQ(bench.count("brackets_started"), 1);
}

// ---------------------------------------------------------------------------
// Brackets not begun

TEST(BracketController, ABallThatDoesNotClipNeedsNoBracket) {
  Bench bench(3);
  bench.clips_above = 1e12;  // nothing clips
  bench.goodFrames(10, 1, 4);
  EXPECT_TRUE(bench.camera.calls.empty());  // good frame 3 asked for nothing
  EXPECT_FALSE(bench.bracket.earlyLadderOut());
  const FrameExposure e = bench.shoot(14);
  bench.arrive(e);
  EXPECT_EQ(bench.start(e), BracketStart::kNotNeeded);
  EXPECT_FALSE(bench.bracket.pending());
  EXPECT_EQ(bench.count("brackets_not_needed"), 1);
  EXPECT_EQ(bench.count("brackets_started"), 0);
  EXPECT_EQ(bench.count("bracket_early_ladders"), 0);
  bench.bracket.fitWithoutBracket();
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 0);
  EXPECT_TRUE(bench.camera.calls.empty());
  EXPECT_EQ(bench.arrive(bench.shoot(15)).role, FrameRole::kPipeline);
}

TEST(BracketController, MaxStopsZeroTurnsTheBracketOff) {
  Bench bench(3, BracketSettings{3.0, 0.0});
  bench.goodFrames(10, 1, 4);
  EXPECT_TRUE(bench.camera.calls.empty());
  const FrameExposure e = bench.shoot(14);
  bench.arrive(e);
  EXPECT_EQ(bench.start(e), BracketStart::kOff);
  EXPECT_FALSE(bench.bracket.pending());
  EXPECT_TRUE(bench.camera.calls.empty());
  // Off is no event: nothing counted.
  for (const char* counter : {"brackets_started", "brackets_not_needed", "brackets_without_exposure_metadata",
                              "brackets_at_shortest_exposure", "brackets_unsupported", "bracket_early_ladders"})
    EXPECT_EQ(bench.count(counter), 0) << counter;
  EXPECT_TRUE(bench.bracket.planLadder(kOwn).exposures.empty());
}

TEST(BracketController, ACameraWithoutExposureControlIsUnsupported) {
  Bench bench(3);
  bench.camera.controllable = false;
  bench.goodFrames(10, 1, 4);  // good frame 3 asks; the camera refuses
  EXPECT_FALSE(bench.bracket.earlyLadderOut());
  EXPECT_EQ(bench.count("bracket_early_ladders"), 0);
  const FrameExposure e = bench.shoot(14);
  bench.arrive(e);
  EXPECT_EQ(bench.start(e), BracketStart::kUnsupported);
  EXPECT_FALSE(bench.bracket.pending());
  EXPECT_EQ(bench.count("brackets_unsupported"), 1);
  EXPECT_EQ(bench.count("brackets_started"), 0);
  ASSERT_FALSE(bench.camera.calls.empty());
  EXPECT_EQ(bench.camera.calls.back().frame, 14u);  // the fit did ask
  bench.bracket.fitWithoutBracket();
  EXPECT_EQ(bench.count("bracket_early_ladders_unused"), 0);
  EXPECT_EQ(bench.arrive(bench.shoot(15)).role, FrameRole::kPipeline);
}

TEST(BracketController, AFrameWithoutExposureMetadataTakesNoBracket) {
  Bench bench(3);
  bench.clips_above = -1.0;  // the ball clips, as far as anyone asks: the metadata is what is missing
  // The source cannot say exposure or gain: no EV can be told.
  for (int good = 1; good <= 4; ++good) {
    const FrameExposure e = bench.shoot(9 + good, {0.0, 0.0});
    ASSERT_EQ(bench.arrive(e).role, FrameRole::kPipeline);
    bench.lead(e, good);
  }
  EXPECT_TRUE(bench.camera.calls.empty());
  EXPECT_FALSE(bench.bracket.earlyLadderOut());
  const FrameExposure e = bench.shoot(14, {0.0, 0.0});
  bench.arrive(e);
  EXPECT_EQ(bench.start(e), BracketStart::kNoExposureMetadata);
  EXPECT_FALSE(bench.bracket.pending());
  EXPECT_EQ(bench.count("brackets_without_exposure_metadata"), 1);
  EXPECT_EQ(bench.count("brackets_started"), 0);
  EXPECT_TRUE(bench.camera.calls.empty());
}

// The gain the metadata does not say (0) is taken as 1, for the base and
// for the rungs.
TEST(BracketController, AFrameThatDoesNotSayItsGainIsTakenAtGainOne) {
  Bench bench(1);
  const FrameExposure e = bench.shoot(10, {8000.0, 0.0});
  bench.arrive(e);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  ASSERT_EQ(bench.camera.calls.size(), 1u);
  // From 8000 us at gain 1: EV -3 is 1000 us.
  expectExposure(bench.camera.calls[0].ladder.at(0), 1000.0, 1.0);
  // 1000 us, gain unsaid: EV -3; still clips (1000 > 500).
  bench.clips_above = 500.0;
  expectBracketFrame(bench.arrive(bench.shoot(11, {1000.0, 0.0})), true, -3.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(12, {125.0, 0.0})), true, -6.0, true);
  const BracketRecord record = bench.bracket.finish();
  expectExposure(record.base, 8000.0, 1.0);
}

TEST(BracketController, AFitFrameAlreadyAtTheShortestExposureTakesNoBracket) {
  Bench bench(3, BracketSettings{}, {100.0, 1.0});
  bench.camera.reported_shortest_us = 100.0;
  bench.clips_above = 50.0;  // clips even at 100 us
  bench.goodFrames(10, 1, 4);
  EXPECT_TRUE(bench.camera.calls.empty());  // no ladder to lead with
  const FrameExposure e = bench.shoot(14);
  bench.arrive(e);
  EXPECT_EQ(bench.start(e), BracketStart::kAtShortestExposure);
  EXPECT_FALSE(bench.bracket.pending());
  EXPECT_EQ(bench.count("brackets_at_shortest_exposure"), 1);
  EXPECT_EQ(bench.count("brackets_started"), 0);
  EXPECT_TRUE(bench.camera.calls.empty());
}

// ---------------------------------------------------------------------------
// How a bracket ends

// The ball clips at every rung: the bracket runs to the ladder's last rung,
// and ends there (the camera delivered all it was asked: nothing clamped).
TEST(BracketController, ALadderRunToItsLastRungEndsThere) {
  Bench bench(1);
  bench.clips_above = 0.0;  // always clips
  const FrameExposure e = bench.shoot(10);
  bench.arrive(e);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  expectBracketFrame(bench.arrive(bench.shoot(11)), true, -3.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(12)), true, -6.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(13)), true, -9.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(14)), true, -12.0, true);
  const BracketRecord record = bench.bracket.finish();
  expectEvs(record.rung_ev, {-3.0, -6.0, -9.0, -12.0});
  EXPECT_EQ(record.latency_frames, 1);
  EXPECT_EQ(bench.count("bracket_frames"), 4);
  EXPECT_EQ(bench.count("bracket_exposures_clamped"), 0);
}

// Shortest exposure reported (100 us): the ladder ends at it; the ball
// still clips there, and asking for less would give the same again: over at
// that rung, counted as clamped.
TEST(BracketController, TheReportedShortestExposureEndsTheBracketAtItsRung) {
  Bench bench(1);
  bench.camera.reported_shortest_us = 100.0;
  bench.camera.sensor_shortest_us = 100.0;
  bench.clips_above = 0.0;
  const FrameExposure e = bench.shoot(10);
  bench.arrive(e);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  ASSERT_EQ(bench.camera.calls.size(), 1u);
  ASSERT_EQ(bench.camera.calls[0].ladder.size(), 3u);
  expectExposure(bench.camera.calls[0].ladder[2], 100.0, 1.0);
  const double shortest_ev = std::log2(100.0 / 16000.0);
  expectBracketFrame(bench.arrive(bench.shoot(11)), true, -3.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(12)), true, -6.0, false);
  EXPECT_EQ(bench.count("bracket_exposures_clamped"), 0);
  expectBracketFrame(bench.arrive(bench.shoot(13)), true, shortest_ev, true);
  EXPECT_EQ(bench.count("bracket_exposures_clamped"), 1);
  const BracketRecord record = bench.bracket.finish();
  EXPECT_TRUE(record.ladder.at_shortest);
  expectEvs(record.rung_ev, {-3.0, -6.0, shortest_ev});
  EXPECT_EQ(bench.count("bracket_frames"), 3);
}

// A sensor that stops at 100 us without saying so: the ladder asks for
// 31.25 and 3.9 us, frames stay at 100 us. That first 100 us frame is a
// rung (1.32 stops below -6); the next three are no shorter: over at the
// third, counted as clamped.
TEST(BracketController, ASensorThatGoesNoShorterThanItSaidEndsThreeFramesAfterItsLastRung) {
  Bench bench(1);
  bench.camera.sensor_shortest_us = 100.0;
  bench.clips_above = 0.0;
  const FrameExposure e = bench.shoot(10);
  bench.arrive(e);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  const double clamped_ev = std::log2(100.0 / 16000.0);
  expectBracketFrame(bench.arrive(bench.shoot(11)), true, -3.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(12)), true, -6.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(13)), true, clamped_ev, false);
  for (std::uint64_t f = 14; f < 14 + BracketController::kClampedAfterFrames - 1; ++f)
    expectBracketFrame(bench.arrive(bench.shoot(f)), false, 0.0, false);
  EXPECT_EQ(bench.count("bracket_exposures_clamped"), 0);
  expectBracketFrame(bench.arrive(bench.shoot(16)), false, 0.0, true);  // the third
  EXPECT_EQ(bench.count("bracket_exposures_clamped"), 1);
  const BracketRecord record = bench.bracket.finish();
  expectEvs(record.rung_ev, {-3.0, -6.0, clamped_ev});
  EXPECT_EQ(bench.count("bracket_frames"), 3);
  EXPECT_EQ(bench.count("bracket_exposures_not_delivered"), 0);
}

// A camera that takes the ladder but never shows it: eight frames waited,
// over at the ninth, with no rung.
TEST(BracketController, NoRungWithinEightFramesEndsTheBracketWithNothing) {
  Bench bench(100);
  const FrameExposure e = bench.shoot(10);
  bench.arrive(e);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  for (std::uint64_t f = 11; f <= 10 + BracketController::kMaxWaitFrames; ++f)
    expectBracketFrame(bench.arrive(bench.shoot(f)), false, 0.0, false);
  EXPECT_EQ(bench.count("bracket_exposures_not_delivered"), 0);
  const FrameArrival last = bench.arrive(bench.shoot(19));
  EXPECT_EQ(last.role, FrameRole::kBracket);
  EXPECT_FALSE(last.keep_as_rung);
  EXPECT_TRUE(last.bracket_over);
  EXPECT_TRUE(last.not_delivered);
  EXPECT_EQ(bench.count("bracket_exposures_not_delivered"), 1);
  EXPECT_EQ(bench.count("bracket_exposures_clamped"), 0);
  const BracketRecord record = bench.bracket.finish();
  EXPECT_TRUE(record.rung_ev.empty());
  EXPECT_EQ(record.latency_frames, -1);
  expectEvs(record.ladder.ev, {-3.0, -6.0, -9.0, -12.0});
  EXPECT_EQ(bench.count("bracket_frames"), 0);
  EXPECT_EQ(bench.bracket.leadFrames(), BracketController::kInitialLeadFrames);  // nothing learnt
  // The frames never left the base: the first after it is shown.
  EXPECT_EQ(bench.arrive(bench.shoot(20)).role, FrameRole::kPipeline);
}

// A frame caught between rungs (the gain applied a frame before the
// exposure time) is kept: its metadata says what it had. One hardly shorter
// than the last kept (less than kNewRungStops) is not, and its ball is not
// looked at.
TEST(BracketController, AFrameCaughtBetweenRungsIsKeptAndOneHardlyShorterIsNot) {
  Bench bench(1);
  const FrameExposure e = bench.shoot(10);
  bench.arrive(e);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  const int questions = bench.clip_questions;
  // 8000 us at gain 1: EV -1.
  expectBracketFrame(bench.arrive(bench.shoot(11, {8000.0, 1.0})), true, -1.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(12, {2000.0, 1.0})), true, -3.0, false);
  // 1500 us: log2(1500 / 2000) = 0.42 stops below the last kept: more than
  // kEvMatchStops, less than kNewRungStops.
  expectBracketFrame(bench.arrive(bench.shoot(13, {1500.0, 1.0})), false, 0.0, false);
  EXPECT_EQ(bench.clip_questions, questions + 2);
  expectBracketFrame(bench.arrive(bench.shoot(14, {250.0, 1.0})), true, -6.0, true);
  EXPECT_EQ(bench.clip_questions, questions + 3);
  const BracketRecord record = bench.bracket.finish();
  expectEvs(record.rung_ev, {-1.0, -3.0, -6.0});
  EXPECT_EQ(record.latency_frames, 1);  // the first frame kept, caught between or not
  EXPECT_EQ(bench.count("bracket_frames"), 3);
}

// After a bracket the camera's AE has moved on: no frame comes back within
// kEvMatchStops of the base. Eight frames are held, then settling gives up.
TEST(BracketController, SettlingGivesUpAfterEightFrames) {
  Bench bench(1);
  const FrameExposure e = bench.shoot(10);
  bench.arrive(e);
  ASSERT_EQ(bench.start(e), BracketStart::kStarted);
  expectBracketFrame(bench.arrive(bench.shoot(11)), true, -3.0, false);
  expectBracketFrame(bench.arrive(bench.shoot(12)), true, -6.0, true);
  bench.bracket.finish();
  bench.camera.setOwn({32000.0, 2.0});  // 2 stops above the base
  for (std::uint64_t f = 13; f < 13 + BracketController::kMaxWaitFrames; ++f) {
    const FrameExposure later = bench.shoot(f);
    ASSERT_NEAR(stopsFrom(later, kOwn), 2.0, kTol);
    EXPECT_EQ(bench.arrive(later).role, FrameRole::kSettling) << "frame " << f;
  }
  EXPECT_EQ(bench.arrive(bench.shoot(21)).role, FrameRole::kPipeline);
  EXPECT_FALSE(bench.bracket.settling());
  EXPECT_EQ(bench.arrive(bench.shoot(22)).role, FrameRole::kPipeline);
}

}  // namespace
}  // namespace probelight
