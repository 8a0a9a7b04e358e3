// The status LED: what it shows for each state, its blink timing, a board
// without the chip (runs without it, said once), and the configuration
// check that keeps it off the button's line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "binary_test_support.hpp"
#include "input/gpio_lines.hpp"
#include "input/status_led.hpp"

namespace probelight {
namespace {

namespace fs = std::filesystem;

TEST(StatusLed, PatternFollowsTheKioskState) {
  EXPECT_EQ(ledPatternFor(false, false), LedPattern::kOff);
  EXPECT_EQ(ledPatternFor(true, false), LedPattern::kOn);
  // A lost camera wins: no recalibration progresses without frames.
  EXPECT_EQ(ledPatternFor(true, true), LedPattern::kBlink);
  EXPECT_EQ(ledPatternFor(false, true), LedPattern::kBlink);
}

TEST(StatusLed, BlinksAtTwoHertzHalfOnAndIsSteadyOtherwise) {
  int lit = 0;
  const int samples = 1000;  // 10 s at 10 ms
  bool previous = ledLitAt(LedPattern::kBlink, 0.0);
  int changes = 0;
  for (int i = 0; i < samples; ++i) {
    const bool now = ledLitAt(LedPattern::kBlink, 100.0 + 0.01 * i);
    lit += now ? 1 : 0;
    changes += now != previous ? 1 : 0;
    previous = now;
  }
  EXPECT_NEAR(static_cast<double>(lit) / samples, 0.5, 0.02);
  EXPECT_NEAR(changes, 40, 1);  // 2 Hz: 4 changes a second over 10 s
  for (const double t : {0.0, 0.3, 12345.6}) {
    EXPECT_TRUE(ledLitAt(LedPattern::kOn, t));
    EXPECT_FALSE(ledLitAt(LedPattern::kOff, t));
  }
}

// Both libgpiod APIs take the chip as configured: v1 looks it up itself, v2
// needs a path (or, for a label, a search among the chips).
TEST(GpioLines, ChipNamesNumbersAndPathsBecomeDevicePaths) {
  EXPECT_EQ(gpioChipPath("gpiochip0"), "/dev/gpiochip0");
  EXPECT_EQ(gpioChipPath("4"), "/dev/gpiochip4");
  EXPECT_EQ(gpioChipPath("/dev/gpiochip4"), "/dev/gpiochip4");
  EXPECT_EQ(gpioChipPath("pinctrl-rp1"), std::nullopt) << "a label is looked up, not guessed";
  EXPECT_EQ(gpioChipPath(""), std::nullopt);
  EXPECT_NE(gpioLibraryDescription().find("libgpiod"), std::string::npos);
}

TEST(StatusLed, MissingChipIsAOneLineReason) {
  StatusLedSettings settings;
  settings.chip = "no-such-gpiochip";
  settings.line = 27;
  GpioStatusLed led(settings);
  std::string error;
  EXPECT_FALSE(led.start(error));
  EXPECT_NE(error.find("status LED: GPIO chip 'no-such-gpiochip' not found"), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos);
  led.set(true);  // harmless without a line
}

class StatusLedRun : public testing::BinaryTest {
 protected:
  StatusLedRun() : BinaryTest("led") {}
};

TEST_F(StatusLedRun, WithoutTheChipTheKioskRunsAndWarnsOnce) {
  const fs::path config = dir_ / "probelight.yaml";
  std::ofstream(config) << "%YAML:1.0\n---\nbutton:\n  chip: no-such-gpiochip\n  led_line: 27\n";
  const fs::path out = dir_ / "out";
  const testing::CommandResult result =
      run("run --frames 3 --save-every 0 --config " + config.string() + " --out " + out.string());
  ASSERT_EQ(result.exit_status, 0) << result.stderr_text;
  EXPECT_EQ(testing::countOccurrences(result.stderr_text, "warning: status LED:"), 1u) << result.stderr_text;
  const nlohmann::json report = readReport(out);
  EXPECT_EQ(report["frames"], 3);
  EXPECT_NE(report["status_led_warning"].get<std::string>().find("no-such-gpiochip"), std::string::npos);
}

TEST_F(StatusLedRun, TheLedCannotShareTheButtonsLine) {
  const fs::path config = dir_ / "probelight.yaml";
  std::ofstream(config) << "%YAML:1.0\n---\nbutton:\n  line: 17\n  led_line: 17\n";
  const testing::CommandResult result = run("run --frames 1 --config " + config.string() + " --out " + (dir_ / "out").string());
  EXPECT_EQ(result.exit_status, 2);
  EXPECT_NE(result.stderr_text.find("button.led_line"), std::string::npos) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find(config.string()), std::string::npos) << result.stderr_text;
}

}  // namespace
}  // namespace probelight
