// The camera's exposure controls over a recalibration with a bracket, fed
// with synthetic events: each control is sent once, on a change; a bracket
// ends by restoring the exposure from before it, then the lock state.
#include <gtest/gtest.h>

#include <vector>

#include "capture/exposure_sequencer.hpp"

namespace probelight {
namespace {

using Kind = ExposureControls::Kind;

TEST(ExposureSequencer, SendsEachChangeOnceAndComesBackFromABracketToWhereItWas) {
  ExposureSequencer sequencer;
  // Start-up: auto, once.
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kAuto);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
  sequencer.onFrame({8000.0, 2.0});
  // The recalibration locks AE.
  sequencer.setLocked(true);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kLocked);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
  sequencer.onFrame({8000.0, 2.0});
  // A bracket: EV -3 then -6, each sent once.
  sequencer.setManual({ExposureSetting{1000.0, 2.0}});
  ExposureControls first = sequencer.nextRequest();
  EXPECT_EQ(first.kind, Kind::kManual);
  EXPECT_DOUBLE_EQ(first.setting.exposure_us, 1000.0);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
  sequencer.onFrame({1000.0, 2.0});  // the bracket frames' metadata must not become the way back
  sequencer.setManual({ExposureSetting{125.0, 2.0}});
  EXPECT_DOUBLE_EQ(sequencer.nextRequest().setting.exposure_us, 125.0);
  sequencer.onFrame({125.0, 2.0});
  // End of the bracket, still locked: the exposure from before it, as a
  // manual value, and nothing more (that is the lock).
  sequencer.setManual({});
  const ExposureControls back = sequencer.nextRequest();
  EXPECT_EQ(back.kind, Kind::kManual);
  EXPECT_DOUBLE_EQ(back.setting.exposure_us, 8000.0);
  EXPECT_DOUBLE_EQ(back.setting.analogue_gain, 2.0);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
  // The fit done: unlock, once.
  sequencer.setLocked(false);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kAuto);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
}

TEST(ExposureSequencer, UnlockedBracketEndsInAutoAndARestartResendsTheState) {
  ExposureSequencer sequencer;
  sequencer.onFrame({5000.0, 1.0});
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kAuto);
  sequencer.setManual({ExposureSetting{625.0, 1.0}});
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kManual);
  sequencer.setManual({});
  const std::vector<Kind> expected = {Kind::kManual, Kind::kAuto, Kind::kNone};
  for (const Kind kind : expected) EXPECT_EQ(sequencer.nextRequest().kind, kind);
  // Ending a bracket that never began changes nothing.
  sequencer.setManual({});
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
  // The camera came back: its new pipeline gets the lock state again.
  sequencer.setLocked(true);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kLocked);
  sequencer.pipelineRestarted();
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kLocked);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
}

TEST(ExposureSequencer, ABracketBeforeAnyFrameEndsInTheLockStateDirectly) {
  ExposureSequencer sequencer;
  sequencer.setLocked(true);
  sequencer.setManual({ExposureSetting{1000.0, 1.0}});
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kManual);
  sequencer.setManual({});
  // Nothing known to restore: the lock's own controls (AE off where it is).
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kLocked);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
}

// A whole ladder asked at once: one rung a request, in order, the last
// held; the source hands over every frame meanwhile. Ended early (the ball
// stopped clipping), the rungs not yet sent are dropped and the way back
// goes out on the very next request.
TEST(ExposureSequencer, ALadderGoesOutOneRungARequestAndEndsWithoutItsRest) {
  ExposureSequencer sequencer;
  sequencer.onFrame({8000.0, 2.0});
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kAuto);
  EXPECT_FALSE(sequencer.inBracket());
  sequencer.setManual({{2000.0, 1.0}, {250.0, 1.0}, {31.0, 1.0}, {4.0, 1.0}});
  EXPECT_TRUE(sequencer.inBracket());
  for (const double exposure_us : {2000.0, 250.0}) {
    const ExposureControls rung = sequencer.nextRequest();
    ASSERT_EQ(rung.kind, Kind::kManual);
    EXPECT_DOUBLE_EQ(rung.setting.exposure_us, exposure_us);
    EXPECT_DOUBLE_EQ(rung.setting.analogue_gain, 1.0);
    sequencer.onFrame(rung.setting);
  }
  // The ball no longer clips: the rest of the ladder is not sent.
  sequencer.setManual({});
  EXPECT_FALSE(sequencer.inBracket());
  const ExposureControls back = sequencer.nextRequest();
  ASSERT_EQ(back.kind, Kind::kManual);
  EXPECT_DOUBLE_EQ(back.setting.exposure_us, 8000.0);
  EXPECT_DOUBLE_EQ(back.setting.analogue_gain, 2.0);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kAuto);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);

  sequencer.onFrame({8000.0, 2.0});  // frames are back at it
  // Run to its end, the last rung is held (sent once), then the way back.
  sequencer.setManual({{2000.0, 1.0}, {250.0, 1.0}});
  EXPECT_DOUBLE_EQ(sequencer.nextRequest().setting.exposure_us, 2000.0);
  EXPECT_DOUBLE_EQ(sequencer.nextRequest().setting.exposure_us, 250.0);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
  sequencer.setManual({});
  EXPECT_DOUBLE_EQ(sequencer.nextRequest().setting.exposure_us, 8000.0);
}

// Two rungs that are the same exposure (a sensor's limit planned twice)
// are one control: nothing is re-sent that the pipeline already has.
TEST(ExposureSequencer, ARepeatedRungIsNotSentAgain) {
  ExposureSequencer sequencer;
  sequencer.onFrame({8000.0, 1.0});
  sequencer.nextRequest();
  sequencer.setManual({{100.0, 1.0}, {100.0, 1.0}, {50.0, 1.0}});
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kManual);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
  const ExposureControls last = sequencer.nextRequest();
  EXPECT_EQ(last.kind, Kind::kManual);
  EXPECT_DOUBLE_EQ(last.setting.exposure_us, 50.0);
}

}  // namespace
}  // namespace probelight
