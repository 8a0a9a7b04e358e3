// The libcamera API differences between Debian bookworm's 0.0.3 and
// Raspberry Pi OS's 0.3-0.5, in one place (selected by libcamera/version.h).
#pragma once

#include <cmath>
#include <cstdint>

#include <memory>
#include <optional>
#include <vector>

#include <libcamera/camera.h>
#include <libcamera/color_space.h>
#include <libcamera/control_ids.h>
#include <libcamera/controls.h>
#include <libcamera/stream.h>
#include <libcamera/version.h>

#include "capture/lens_focus_choice.hpp"
#include "core/ycbcr.hpp"

namespace probelight::libcamera_adapter {

// generateConfiguration takes a std::vector<StreamRole> in 0.0.x and a
// Span<const StreamRole> from 0.1 on; a vector converts to both.
inline std::unique_ptr<libcamera::CameraConfiguration> viewfinderConfiguration(libcamera::Camera& camera) {
  const std::vector<libcamera::StreamRole> roles{libcamera::StreamRole::Viewfinder};
  return camera.generateConfiguration(roles);
}

// The file descriptor of a frame buffer plane: a SharedFD in every version
// since 0.0.1 (it was a plain FileDescriptor before).
template <typename Plane>
int planeFd(const Plane& plane) {
  return plane.fd.get();
}

// Sets a control the camera has (`supported`: Camera::controls()); one it
// lacks is left out. libcamera logs an ERROR for each invalid control in
// each request (vimc's sensor has no AeEnable or AwbEnable), which would
// flood the journal. A request's own list knows the ids only, not the
// camera's map (its infoMap() is null), hence the map passed in.
template <typename T, typename V>
inline void setIfSupported(libcamera::ControlList& controls, const libcamera::ControlInfoMap& supported,
                           const libcamera::Control<T>& control, const V& value) {
  if (supported.find(control.id()) == supported.end()) return;
  controls.set(control, value);
}
// The same for a list made from the camera's map (the start controls).
template <typename T, typename V>
inline void setIfSupported(libcamera::ControlList& controls, const libcamera::Control<T>& control, const V& value) {
  const libcamera::ControlInfoMap* supported = controls.infoMap();
  if (supported != nullptr && supported->find(control.id()) == supported->end()) return;
  controls.set(control, value);
}

// Freezes (locked) or releases auto exposure, gain and white balance. 0.5
// split AeEnable into ExposureTimeMode and AnalogueGainMode (AeEnable stays,
// input-only, as a shorthand for both); switching them to manual without a
// value keeps the last values AE chose, as AeEnable false did before.
inline void setExposureLocked(libcamera::ControlList& controls, const libcamera::ControlInfoMap& supported, bool locked) {
#if LIBCAMERA_VERSION_MAJOR > 0 || LIBCAMERA_VERSION_MINOR >= 5
  setIfSupported(controls, supported, libcamera::controls::ExposureTimeMode,
                 locked ? libcamera::controls::ExposureTimeModeManual : libcamera::controls::ExposureTimeModeAuto);
  setIfSupported(controls, supported, libcamera::controls::AnalogueGainMode,
                 locked ? libcamera::controls::AnalogueGainModeManual : libcamera::controls::AnalogueGainModeAuto);
#else
  setIfSupported(controls, supported, libcamera::controls::AeEnable, !locked);
#endif
  setIfSupported(controls, supported, libcamera::controls::AwbEnable, !locked);
}

// A fixed exposure time (microseconds) and analogue gain, AE off (0.5's
// manual modes, AeEnable false before it). The sensor may clamp them; the
// frame's metadata says what it used.
inline void setManualExposure(libcamera::ControlList& controls, const libcamera::ControlInfoMap& supported,
                              double exposure_us, double analogue_gain) {
#if LIBCAMERA_VERSION_MAJOR > 0 || LIBCAMERA_VERSION_MINOR >= 5
  setIfSupported(controls, supported, libcamera::controls::ExposureTimeMode, libcamera::controls::ExposureTimeModeManual);
  setIfSupported(controls, supported, libcamera::controls::AnalogueGainMode, libcamera::controls::AnalogueGainModeManual);
#else
  setIfSupported(controls, supported, libcamera::controls::AeEnable, false);
#endif
  setIfSupported(controls, supported, libcamera::controls::ExposureTime, static_cast<std::int32_t>(std::lround(exposure_us)));
  setIfSupported(controls, supported, libcamera::controls::AnalogueGain, static_cast<float>(analogue_gain));
  setIfSupported(controls, supported, libcamera::controls::AwbEnable, false);
}

// The shortest exposure time the camera takes (microseconds): the minimum
// of its ExposureTime control (an int32 in every version), or nullopt when
// it does not say.
inline std::optional<double> exposureTimeMinUs(const libcamera::Camera& camera) {
  const libcamera::ControlInfoMap& info = camera.controls();
  const auto entry = info.find(libcamera::controls::ExposureTime.id());
  if (entry == info.end() || entry->second.min().type() != libcamera::ControlTypeInteger32) return std::nullopt;
  const std::int32_t shortest_us = entry->second.min().get<std::int32_t>();
  if (shortest_us <= 0) return std::nullopt;
  return static_cast<double>(shortest_us);
}

// Whether the camera takes a manual exposure time at all. vimc's sensor,
// for one, has no ExposureTime control: it ignores one set in a request.
inline bool hasExposureTimeControl(const libcamera::Camera& camera) {
  const libcamera::ControlInfoMap& info = camera.controls();
  return info.find(libcamera::controls::ExposureTime.id()) != info.end();
}

// What the camera offers for its lens. AfMode (int32) and LensPosition
// (float, dioptres) are in libcamera's core controls from 0.0.3 on, with
// the same types.
inline LensControlsOffered lensControlsOffered(const libcamera::Camera& camera) {
  const libcamera::ControlInfoMap& info = camera.controls();
  LensControlsOffered offered;
  offered.af_mode = info.find(libcamera::controls::AfMode.id()) != info.end();
  const auto position = info.find(libcamera::controls::LensPosition.id());
  offered.lens_position = position != info.end();
  if (offered.lens_position && position->second.min().type() == libcamera::ControlTypeFloat &&
      position->second.max().type() == libcamera::ControlTypeFloat) {
    offered.min_dioptres = position->second.min().get<float>();
    offered.max_dioptres = position->second.max().get<float>();
  }
  return offered;
}

// The focus controls `focus` asks for; none when it asks for none.
inline void setFocus(libcamera::ControlList& controls, const FocusRequest& focus) {
  if (!focus.lens_position_dioptres) return;
  if (focus.af_mode_manual) setIfSupported(controls, libcamera::controls::AfMode, libcamera::controls::AfModeManual);
  setIfSupported(controls, libcamera::controls::LensPosition, static_cast<float>(*focus.lens_position_dioptres));
}

// The Y'CbCr encoding of a validated stream. No colour space (old pipeline
// handlers) means what they produce: JPEG's full-range Rec601.
inline YcbcrEncoding encodingOf(const std::optional<libcamera::ColorSpace>& color_space) {
  if (!color_space) return YcbcrEncoding{YcbcrMatrix::kRec601, true};
  YcbcrEncoding encoding;
  switch (color_space->ycbcrEncoding) {
    case libcamera::ColorSpace::YcbcrEncoding::Rec709: encoding.matrix = YcbcrMatrix::kRec709; break;
    case libcamera::ColorSpace::YcbcrEncoding::Rec2020: encoding.matrix = YcbcrMatrix::kRec2020; break;
    default: encoding.matrix = YcbcrMatrix::kRec601; break;
  }
  encoding.full_range = color_space->range == libcamera::ColorSpace::Range::Full;
  return encoding;
}

}  // namespace probelight::libcamera_adapter
