// Pinhole projection with OpenCV's 5-term distortion, written out here (not
// calling OpenCV) because the same formulas run in the shaders; tests check
// both against cv::projectPoints.
#pragma once

#include <glm/glm.hpp>

#include "core/types.hpp"

namespace probelight::ibl {

// Camera-frame point (z > 0) to distorted pixel coordinates. A point with
// z = 0 or non-finite coordinates gives a non-finite pixel (never a crash);
// callers that can meet such points check std::isfinite (reflectedDirectionToPixel
// and computeProbeOutline return empty / invalid). Zero would be a real pixel.
glm::dvec2 projectToPixel(const CameraIntrinsics& camera, const glm::dvec3& point_cam);
// The most fixed-point steps pixelToCameraRay takes (OpenCV's undistortPoints scheme,
// which defaults to 5). The error shrinks each step by roughly the slope of the
// distortion, |d(distortion)/dx| ~ 3|k1| r^2 + 5|k2| r^4. Over a whole
// 640x480, f = 525 frame with k1 = -0.28, k2 = 0.07 (stronger than a webcam)
// 15 steps reach 1e-9 (tests/ibl measures it with cv::undistortPoints); 25
// leaves margin for stronger lenses; it stops early once a step moves the
// point by less than 1e-14 (normalised). A shader may take fewer where the lens is mild.
constexpr int kUndistortIterations = 25;

// Distorted pixel to the undistorted ray (x, y, 1) in the camera frame,
// by fixed-point iteration on the distortion model. Pixel coordinates are
// OpenCV's: the same frame projectToPixel returns.
glm::dvec3 pixelToCameraRay(const CameraIntrinsics& camera, const glm::dvec2& pixel);

}  // namespace probelight::ibl
