// The button's debounce state machine, fed with synthetic bounce, and the
// GPIO button's failure path on a machine without GPIO.
#include <cstdint>
#include <filesystem>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "input/debounce.hpp"
#include "input/gpio_button.hpp"

namespace probelight {
namespace {

constexpr std::int64_t kMs = 1'000'000;

struct Recorder {
  ButtonDebouncer debouncer;
  std::vector<ButtonEvent::Kind> events;
  explicit Recorder(DebounceSettings settings = {}) : debouncer(settings) {}
  void level(std::int64_t t, bool pressed) {
    for (auto e : debouncer.onLevel(t, pressed)) events.push_back(e);
  }
  // Time passing, checked every 5 ms as GpioButton's thread does.
  void idleUntil(std::int64_t from, std::int64_t to) {
    for (std::int64_t t = from; t <= to; t += 5 * kMs)
      for (auto e : debouncer.onTime(t)) events.push_back(e);
  }
  int count(ButtonEvent::Kind kind) const {
    int n = 0;
    for (auto e : events) n += e == kind ? 1 : 0;
    return n;
  }
};

// 50 edges within 10 ms, alternating, ending on `final_level`.
void bounce(Recorder& r, std::int64_t start, bool final_level, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<std::int64_t> gap(50'000, 350'000);  // 0.05-0.35 ms: 50 edges fit in ~10 ms
  std::int64_t t = start;
  bool level = !final_level;
  for (int edge = 0; edge < 50; ++edge) {
    level = edge == 49 ? final_level : !level;
    r.level(t, level);
    t += gap(random);
  }
  ASSERT_LE(t - start, 20 * kMs);
}

TEST(ButtonDebouncer, FiftyBouncingEdgesOnPressAndOnReleaseGiveExactlyOnePress) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    Recorder r;
    bounce(r, 100 * kMs, true, seed);   // pressed, bouncing
    r.idleUntil(120 * kMs, 400 * kMs);  // held ~0.3 s
    bounce(r, 400 * kMs, false, seed + 100);  // released, bouncing
    r.idleUntil(420 * kMs, 600 * kMs);
    EXPECT_EQ(r.count(ButtonEvent::Kind::kPress), 1) << "seed " << seed;
    EXPECT_EQ(r.count(ButtonEvent::Kind::kLongPress), 0) << "seed " << seed;
  }
}

TEST(ButtonDebouncer, GlitchesShorterThanTheDebounceTimeAreNotPresses) {
  Recorder r;
  r.idleUntil(0, 100 * kMs);
  for (int k = 0; k < 20; ++k) {  // 1 ms spikes every 50 ms (interference)
    r.level((150 + 50 * k) * kMs, true);
    r.level((151 + 50 * k) * kMs, false);
    r.idleUntil((152 + 50 * k) * kMs, (199 + 50 * k) * kMs);
  }
  EXPECT_TRUE(r.events.empty());
}

TEST(ButtonDebouncer, HoldingGivesOneLongPressAndNoPress) {
  Recorder r;
  bounce(r, 0, true, 7);
  r.idleUntil(20 * kMs, 4000 * kMs);  // held 4 s
  EXPECT_EQ(r.count(ButtonEvent::Kind::kLongPress), 1);
  bounce(r, 4000 * kMs, false, 8);
  r.idleUntil(4020 * kMs, 4200 * kMs);
  EXPECT_EQ(r.count(ButtonEvent::Kind::kLongPress), 1);
  EXPECT_EQ(r.count(ButtonEvent::Kind::kPress), 0) << "the release after a long press is not a press";
  // The long press comes when the hold reaches 3 s (of a settled press), not at the release.
  Recorder timing;
  timing.level(0, true);
  timing.idleUntil(0, 2990 * kMs);
  EXPECT_TRUE(timing.events.empty());
  timing.idleUntil(3000 * kMs, 3010 * kMs);
  EXPECT_EQ(timing.count(ButtonEvent::Kind::kLongPress), 1);
}

TEST(ButtonDebouncer, TwoQuickPressesAreTwoPressesAndAButtonHeldAtStartIsNone) {
  Recorder r;
  r.level(0, true);
  r.idleUntil(5 * kMs, 100 * kMs);
  r.level(100 * kMs, false);
  r.idleUntil(105 * kMs, 200 * kMs);
  r.level(200 * kMs, true);
  r.idleUntil(205 * kMs, 300 * kMs);
  r.level(300 * kMs, false);
  r.idleUntil(305 * kMs, 400 * kMs);
  EXPECT_EQ(r.count(ButtonEvent::Kind::kPress), 2);
  // Held when probelight starts (someone leaning on it): its release is not a press.
  ButtonDebouncer held(DebounceSettings{}, true);
  std::vector<ButtonEvent::Kind> events = held.onLevel(0, true);
  events = held.onLevel(500 * kMs, false);
  const auto later = held.onTime(600 * kMs);
  EXPECT_TRUE(events.empty() && later.empty());
}

// This machine has no GPIO chip: the button says which chip it looked for
// and why it may be missing, and the kiosk then runs without it
// (EndToEnd.GpioButtonWithoutAChipWarnsAndRuns).
TEST(GpioButton, MissingChipIsAClearError) {
  if (std::filesystem::exists("/dev/gpiochip0")) GTEST_SKIP() << "this machine has a GPIO chip";
  GpioButtonSettings settings;
  settings.chip = "gpiochip0";
  GpioButton button(settings);
  std::string error;
  EXPECT_FALSE(button.start(error));
  EXPECT_NE(error.find("GPIO chip 'gpiochip0' not found"), std::string::npos) << error;
  EXPECT_NE(error.find("gpio"), std::string::npos) << error;
  EXPECT_TRUE(button.poll().empty());
}

}  // namespace
}  // namespace probelight
