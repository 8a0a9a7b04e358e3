// `probelight calibrate-camera`: a chessboard calibration with OpenCV that
// writes camera.yaml in the project's format (config::saveCameraFile).
//
// Views are rejected, each with its reason on the log, when the file cannot
// be read, its size differs from the first readable view's, the board is not
// found, or (after a first fit) its reprojection error is an outlier. The
// command fails with exit status 2 and one line when fewer than
// kMinCalibrationViews usable views remain.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include "app/command_line.hpp"

namespace probelight {

// Why 5: the fit has 9 intrinsic unknowns (fx, fy, cx, cy, k1, k2, p1, p2,
// k3) besides each view's pose, and needs the board in several places and
// tilts to tell them apart. Measured on tests/data/chessboard, 200 random
// k-view subsets each, against the 13-view fit: worst fx error 6.5% (k=3),
// 2.8% (4), 2.4% (5), 1.9% (6), 1.3% (8); worst principal point error 22,
// 20, 14, 8.7, 5.0 px. There is no sharp knee past 3; 5 is where the worst
// case first drops below 15 px and 2.5%, a floor that stops a result that is
// more guess than measurement, not a recommendation: take 10-20 views.
inline constexpr int kMinCalibrationViews = 5;

// A view whose RMS reprojection error exceeds both this multiple of the
// median view's and kOutlierFloorPx is dropped and the fit redone once.
inline constexpr double kOutlierMedianFactor = 3.0;
inline constexpr double kOutlierFloorPx = 1.0;

// The per-view RMS above which a view is an outlier:
// max(kOutlierMedianFactor * median, kOutlierFloorPx). `view_rms_px` not empty.
double outlierLimitPx(std::vector<double> view_rms_px);

// Exit status: 0 written; 2 bad flag, no matching file, too few usable
// views, or camera.yaml not writable; 1 OpenCV failed inside the fit.
int runCalibrateCamera(const CalibrateCameraOptions& options, std::ostream& out, std::ostream& log);

}  // namespace probelight
