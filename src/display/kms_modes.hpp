// Which screen and which mode the kiosk shows on: a pure choice over a
// description of the KMS connectors (what libdrm reports), so that it is
// tested against described hardware, and the conversion from libdrm's
// structures to that description.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <xf86drmMode.h>

namespace probelight {

struct ModeDescription {
  int width_px = 0;
  int height_px = 0;
  double refresh_hz = 0.0;
  bool preferred = false;  // DRM_MODE_TYPE_PREFERRED: the panel's native mode
};

struct ConnectorDescription {
  std::uint32_t id = 0;
  std::string name;  // "HDMI-A-1", as the kernel names it (type name - type id)
  bool connected = false;
  std::vector<ModeDescription> modes;  // in the driver's order
};

// From probelight.yaml (display section): empty / zero fields mean "any".
struct ModeRequest {
  std::string connector;  // e.g. "HDMI-A-2"; empty: the first connected
  int width_px = 0;       // 0: the connector's preferred mode
  int height_px = 0;
  double refresh_hz = 0.0;  // 0: the highest refresh at that size
};

struct ModeChoice {
  std::size_t connector_index = 0;
  std::size_t mode_index = 0;
  std::string summary;  // "HDMI-A-1 1920x1080@60.00"
};

// The first connected connector (or the named one) and its preferred mode
// (or the one asked for). nullopt with a one-line error that lists what
// there is when nothing fits.
std::optional<ModeChoice> chooseMode(const std::vector<ConnectorDescription>& connectors, const ModeRequest& request,
                                     std::string& error);

// libdrm's structures to the description.
ModeDescription describeMode(const drmModeModeInfo& mode);
ConnectorDescription describeConnector(const drmModeConnector& connector);

}  // namespace probelight
