#include "display/kms_modes.hpp"

#include <cmath>
#include <cstdio>

#include <xf86drm.h>

namespace probelight {

namespace {

std::string modeText(const ModeDescription& mode) {
  char text[64];
  std::snprintf(text, sizeof text, "%dx%d@%.2f", mode.width_px, mode.height_px, mode.refresh_hz);
  return text;
}

}  // namespace

ModeDescription describeMode(const drmModeModeInfo& mode) {
  ModeDescription description;
  description.width_px = mode.hdisplay;
  description.height_px = mode.vdisplay;
  // The exact refresh from the timings (mode.vrefresh is rounded).
  if (mode.htotal > 0 && mode.vtotal > 0) {
    double refresh = mode.clock * 1000.0 / (static_cast<double>(mode.htotal) * mode.vtotal);
    if (mode.flags & DRM_MODE_FLAG_INTERLACE) refresh *= 2.0;
    if (mode.flags & DRM_MODE_FLAG_DBLSCAN) refresh /= 2.0;
    if (mode.vscan > 1) refresh /= mode.vscan;
    description.refresh_hz = refresh;
  } else {
    description.refresh_hz = mode.vrefresh;
  }
  description.preferred = (mode.type & DRM_MODE_TYPE_PREFERRED) != 0;
  return description;
}

ConnectorDescription describeConnector(const drmModeConnector& connector) {
  ConnectorDescription description;
  description.id = connector.connector_id;
  const char* type = drmModeGetConnectorTypeName(connector.connector_type);
  description.name = std::string(type ? type : "Unknown") + "-" + std::to_string(connector.connector_type_id);
  description.connected = connector.connection == DRM_MODE_CONNECTED;
  for (int i = 0; i < connector.count_modes; ++i) description.modes.push_back(describeMode(connector.modes[i]));
  return description;
}

std::optional<ModeChoice> chooseMode(const std::vector<ConnectorDescription>& connectors, const ModeRequest& request,
                                     std::string& error) {
  std::string available;
  for (const ConnectorDescription& c : connectors)
    available += (available.empty() ? "" : ", ") + c.name + (c.connected ? "" : " (nothing plugged in)");
  if (available.empty()) available = "none";
  std::optional<std::size_t> chosen;
  for (std::size_t i = 0; i < connectors.size() && !chosen; ++i) {
    const ConnectorDescription& c = connectors[i];
    if (!request.connector.empty() ? c.name == request.connector : c.connected && !c.modes.empty()) chosen = i;
  }
  if (!chosen) {
    error = request.connector.empty() ? "no screen is connected (connectors: " + available + ")"
                                      : "no connector " + request.connector + " (connectors: " + available + ")";
    return std::nullopt;
  }
  const ConnectorDescription& connector = connectors[*chosen];
  if (!connector.connected || connector.modes.empty()) {
    error = "connector " + connector.name + " has no screen plugged in";
    return std::nullopt;
  }
  std::optional<std::size_t> mode;
  if (request.width_px <= 0 || request.height_px <= 0) {
    for (std::size_t m = 0; m < connector.modes.size() && !mode; ++m)
      if (connector.modes[m].preferred) mode = m;
    if (!mode) mode = 0;  // no preferred mode: the driver lists the best first
  } else {
    for (std::size_t m = 0; m < connector.modes.size(); ++m) {
      const ModeDescription& d = connector.modes[m];
      if (d.width_px != request.width_px || d.height_px != request.height_px) continue;
      if (request.refresh_hz > 0.0 && std::abs(d.refresh_hz - request.refresh_hz) > 0.5) continue;
      if (!mode || d.refresh_hz > connector.modes[*mode].refresh_hz) mode = m;
    }
    if (!mode) {
      std::string offered;
      for (const ModeDescription& d : connector.modes) offered += (offered.empty() ? "" : ", ") + modeText(d);
      error = "connector " + connector.name + " does not offer " + std::to_string(request.width_px) + "x" +
              std::to_string(request.height_px) +
              (request.refresh_hz > 0.0 ? "@" + std::to_string(static_cast<int>(std::lround(request.refresh_hz))) : "") +
              " (it offers " + offered + ")";
      return std::nullopt;
    }
  }
  ModeChoice choice;
  choice.connector_index = *chosen;
  choice.mode_index = *mode;
  choice.summary = connector.name + " " + modeText(connector.modes[*mode]);
  return choice;
}

}  // namespace probelight
