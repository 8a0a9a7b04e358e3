// The window's keys (input/window_keys) and where a frame lands in a
// resized window (display/letterbox_blit's letterboxRect): pure, no window.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "display/letterbox_blit.hpp"
#include "input/window_keys.hpp"

namespace probelight {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(WindowKeys, ATapIsAPressOnRelease) {
  WindowKeys keys(3000.0);
  EXPECT_TRUE(keys.onKey(WindowKey::kButton, true, false, 0).button.empty());  // could still become a long press
  const WindowActions up = keys.onKey(WindowKey::kButton, false, false, 200 * kMs);
  ASSERT_EQ(up.button.size(), 1u);
  EXPECT_EQ(up.button[0], ButtonEvent::Kind::kPress);
}

TEST(WindowKeys, HeldItIsOneLongPressWhileHeldAndNothingOnRelease) {
  WindowKeys keys(3000.0);
  keys.onKey(WindowKey::kButton, true, false, 0);
  // The window system's auto-repeat while it is held adds nothing.
  for (int t = 500; t < 3000; t += 33) EXPECT_TRUE(keys.onKey(WindowKey::kButton, true, true, t * kMs).button.empty());
  EXPECT_TRUE(keys.onTime(2999 * kMs).button.empty());
  const WindowActions due = keys.onTime(3000 * kMs);
  ASSERT_EQ(due.button.size(), 1u);
  EXPECT_EQ(due.button[0], ButtonEvent::Kind::kLongPress);
  EXPECT_TRUE(keys.onTime(5000 * kMs).button.empty());
  EXPECT_TRUE(keys.onKey(WindowKey::kButton, false, false, 5100 * kMs).button.empty());
  // And the next tap is a tap again.
  keys.onKey(WindowKey::kButton, true, false, 6000 * kMs);
  EXPECT_EQ(keys.onKey(WindowKey::kButton, false, false, 6100 * kMs).button.size(), 1u);
}

TEST(WindowKeys, SaveAndQuitOnTheKeyGoingDownOnly) {
  WindowKeys keys;
  EXPECT_EQ(keys.onKey(WindowKey::kSave, true, false, 0).saves, 1);
  EXPECT_EQ(keys.onKey(WindowKey::kSave, true, true, 30 * kMs).saves, 0);  // auto-repeat: not another save
  EXPECT_EQ(keys.onKey(WindowKey::kSave, false, false, 60 * kMs).saves, 0);
  EXPECT_FALSE(keys.onKey(WindowKey::kOther, true, false, 70 * kMs).quit);
  EXPECT_TRUE(keys.onKey(WindowKey::kQuit, true, false, 80 * kMs).quit);
  WindowActions both;
  both.add(keys.onKey(WindowKey::kSave, true, false, 90 * kMs));
  both.add(keys.onKey(WindowKey::kQuit, true, false, 95 * kMs));
  EXPECT_EQ(both.saves, 1);
  EXPECT_TRUE(both.quit);
}

TEST(Letterbox, FillsTheLimitingSideAndCentresTheOther) {
  const ScreenRect wide = letterboxRect(640, 480, 1000, 500);
  EXPECT_EQ(wide.width, 667);
  EXPECT_EQ(wide.height, 500);
  EXPECT_EQ(wide.x, 166);
  EXPECT_EQ(wide.y, 0);
  const ScreenRect tall = letterboxRect(640, 480, 800, 1200);
  EXPECT_EQ(tall.width, 800);
  EXPECT_EQ(tall.height, 600);
  EXPECT_EQ(tall.y, 300);
  const ScreenRect same = letterboxRect(640, 480, 640, 480);
  EXPECT_EQ(same.x, 0);
  EXPECT_EQ(same.width, 640);
  EXPECT_EQ(same.height, 480);
  EXPECT_EQ(letterboxRect(640, 480, 0, 480).width, 0);
  EXPECT_EQ(letterboxRect(0, 480, 640, 480).width, 0);
}

// Any sizes: inside the screen, touching two opposite edges, the aspect
// kept to what whole pixels allow (half a pixel on the rounded side).
TEST(Letterbox, KeepsTheAspectToHalfAPixelForAnySizes) {
  std::mt19937 random(7);
  std::uniform_int_distribution<int> size(1, 4000);
  for (int i = 0; i < 20000; ++i) {
    const int fw = size(random), fh = size(random), sw = size(random), sh = size(random);
    const ScreenRect r = letterboxRect(fw, fh, sw, sh);
    ASSERT_GE(r.x, 0);
    ASSERT_GE(r.y, 0);
    ASSERT_LE(r.x + r.width, sw);
    ASSERT_LE(r.y + r.height, sh);
    ASSERT_TRUE(r.width == sw || r.height == sh);
    const double expected_height = static_cast<double>(r.width) * fh / fw;
    const double expected_width = static_cast<double>(r.height) * fw / fh;
    ASSERT_TRUE(std::abs(r.height - expected_height) <= 0.5 + 1e-9 || std::abs(r.width - expected_width) <= 0.5 + 1e-9 ||
                r.width == 1 || r.height == 1)
        << fw << "x" << fh << " on " << sw << "x" << sh << ": " << r.width << "x" << r.height;
  }
}

}  // namespace
}  // namespace probelight
