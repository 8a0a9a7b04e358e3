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
  sequencer.setManual(ExposureSetting{1000.0, 2.0});
  ExposureControls first = sequencer.nextRequest();
  EXPECT_EQ(first.kind, Kind::kManual);
  EXPECT_DOUBLE_EQ(first.setting.exposure_us, 1000.0);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
  sequencer.onFrame({1000.0, 2.0});  // the bracket frames' metadata must not become the way back
  sequencer.setManual(ExposureSetting{125.0, 2.0});
  EXPECT_DOUBLE_EQ(sequencer.nextRequest().setting.exposure_us, 125.0);
  sequencer.onFrame({125.0, 2.0});
  // End of the bracket, still locked: the exposure from before it, as a
  // manual value, and nothing more (that is the lock).
  sequencer.setManual(std::nullopt);
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
  sequencer.setManual(ExposureSetting{625.0, 1.0});
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kManual);
  sequencer.setManual(std::nullopt);
  const std::vector<Kind> expected = {Kind::kManual, Kind::kAuto, Kind::kNone};
  for (const Kind kind : expected) EXPECT_EQ(sequencer.nextRequest().kind, kind);
  // Ending a bracket that never began changes nothing.
  sequencer.setManual(std::nullopt);
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
  sequencer.setManual(ExposureSetting{1000.0, 1.0});
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kManual);
  sequencer.setManual(std::nullopt);
  // Nothing known to restore: the lock's own controls (AE off where it is).
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kLocked);
  EXPECT_EQ(sequencer.nextRequest().kind, Kind::kNone);
}

}  // namespace
}  // namespace probelight
