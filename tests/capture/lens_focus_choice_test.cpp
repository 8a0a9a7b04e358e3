// Which focus controls a source sends (issue 48): camera.yaml's lens
// position with autofocus off where the camera can drive its lens, nothing
// where the file names none, and one warning line where the camera has no
// lens control. The libcamera source and the simulated camera both send
// what this says; no camera here has a lens, so the choice is tested alone.
#include <gtest/gtest.h>

#include "capture/lens_focus_choice.hpp"

namespace probelight {
namespace {

// The Camera Module 3 as libcamera 0.0.3-0.4 describe its IMX708: AfMode,
// and LensPosition from 0 (infinity) to 32 dioptres.
const LensControlsOffered kCameraModule3{true, true, 0.0, 32.0};

TEST(LensFocusChoice, ACameraWithALensIsHeldAtCameraYamlsPositionWithAutofocusOff) {
  const FocusRequest held = chooseFocusRequest(2.5, kCameraModule3, "imx708");
  ASSERT_TRUE(held.lens_position_dioptres.has_value());
  EXPECT_EQ(*held.lens_position_dioptres, 2.5);
  EXPECT_TRUE(held.af_mode_manual);
  EXPECT_EQ(held.warning, "");
  // Infinity (0) and the nearest focus (32) are positions like any other.
  EXPECT_EQ(chooseFocusRequest(0.0, kCameraModule3, "imx708").lens_position_dioptres, 0.0);
  EXPECT_EQ(chooseFocusRequest(32.0, kCameraModule3, "imx708").warning, "");
  // A lens that is driven but has no autofocus to turn off gets no AfMode.
  const FocusRequest no_autofocus = chooseFocusRequest(2.5, {true, false, 0.0, 32.0}, "lens-only");
  EXPECT_EQ(no_autofocus.lens_position_dioptres, 2.5);
  EXPECT_FALSE(no_autofocus.af_mode_manual);
  // A lens that does not report its range is sent the position as written.
  EXPECT_EQ(chooseFocusRequest(40.0, {true, true, std::nullopt, std::nullopt}, "unranged").lens_position_dioptres,
            40.0);
}

TEST(LensFocusChoice, WithoutAPositionInCameraYamlNoFocusControlIsSent) {
  for (const LensControlsOffered& offered : {kCameraModule3, LensControlsOffered{}}) {
    const FocusRequest none = chooseFocusRequest(std::nullopt, offered, "any");
    EXPECT_FALSE(none.lens_position_dioptres.has_value());
    EXPECT_FALSE(none.af_mode_manual);
    EXPECT_EQ(none.warning, "");
  }
}

TEST(LensFocusChoice, ACameraWithoutALensControlIsOneWarningLineAndNoControl) {
  // vimc's sensor, or a fixed-focus module (the Camera Module 2's IMX219).
  const FocusRequest fixed = chooseFocusRequest(2.5, LensControlsOffered{}, "platform/vimc.0 Sensor B");
  EXPECT_FALSE(fixed.lens_position_dioptres.has_value());
  EXPECT_FALSE(fixed.af_mode_manual);
  EXPECT_EQ(fixed.warning,
            "camera: platform/vimc.0 Sensor B has no lens control (LensPosition), so camera.yaml's "
            "lens_position_dioptres 2.5 is not set: right for a fixed-focus lens, which cannot move off its "
            "calibration");
  // An autofocus without a position to hold cannot keep the calibration either.
  const FocusRequest af_only = chooseFocusRequest(2.5, {false, true, std::nullopt, std::nullopt}, "af-only");
  EXPECT_FALSE(af_only.lens_position_dioptres.has_value());
  EXPECT_FALSE(af_only.af_mode_manual);
  EXPECT_NE(af_only.warning.find("has no lens control"), std::string::npos) << af_only.warning;
}

TEST(LensFocusChoice, APositionPastTheLensesRangeIsClampedAndSaidOnce) {
  const FocusRequest far = chooseFocusRequest(40.0, kCameraModule3, "imx708");
  EXPECT_EQ(far.lens_position_dioptres, 32.0);
  EXPECT_TRUE(far.af_mode_manual);
  EXPECT_EQ(far.warning, "camera: imx708's lens reaches 0 to 32 dioptres, so camera.yaml's lens_position_dioptres 40 "
                         "is set as 32: the intrinsics may not hold (was camera.yaml calibrated with another camera?)");
  const FocusRequest near_limit = chooseFocusRequest(0.5, {true, true, 1.0, 15.0}, "short-lens");
  EXPECT_EQ(near_limit.lens_position_dioptres, 1.0);
  EXPECT_NE(near_limit.warning.find("set as 1:"), std::string::npos) << near_limit.warning;
  EXPECT_EQ(near_limit.warning.find('\n'), std::string::npos);
}

}  // namespace
}  // namespace probelight
