#include "passes/dmabuf_import_check.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace probelight::passes {

std::string fourccName(std::uint32_t drm_fourcc) {
  std::string name;
  for (int shift = 0; shift < 32; shift += 8) {
    const char c = static_cast<char>((drm_fourcc >> shift) & 0xffu);
    const bool printable = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
    name += printable ? c : '?';
  }
  return name;
}

std::string dmabufImportObstacle(std::uint32_t drm_fourcc, const std::vector<DmabufPlaneLayout>& planes,
                                 const std::optional<std::vector<std::uint32_t>>& driver_formats) {
  for (std::size_t p = 0; p < planes.size(); ++p) {
    const DmabufPlaneLayout& plane = planes[p];
    const std::string which = "plane layout: plane " + std::to_string(p) + "'s ";
    if (plane.rows <= 0 || plane.row_bytes <= 0) return which + "size is empty";
    if (plane.pitch_bytes < plane.row_bytes)
      return which + "pitch " + std::to_string(plane.pitch_bytes) + " bytes is shorter than its row of " +
             std::to_string(plane.row_bytes);
    if (!plane.buffer_size_bytes) continue;
    // The last row needs only its own bytes, not a whole pitch.
    const std::uint64_t end = plane.offset_bytes +
                              static_cast<std::uint64_t>(plane.pitch_bytes) * static_cast<std::uint64_t>(plane.rows - 1) +
                              static_cast<std::uint64_t>(plane.row_bytes);
    if (end > *plane.buffer_size_bytes)
      return which + "rows end at byte " + std::to_string(end) + " (offset " + std::to_string(plane.offset_bytes) +
             " + pitch " + std::to_string(plane.pitch_bytes) + " x " + std::to_string(plane.rows) +
             " rows), past its dmabuf's " + std::to_string(*plane.buffer_size_bytes) + " bytes";
  }
  if (driver_formats && std::find(driver_formats->begin(), driver_formats->end(), drm_fourcc) == driver_formats->end()) {
    std::string offered;
    for (std::uint32_t format : *driver_formats) {
      if (!offered.empty()) offered += ' ';
      offered += fourccName(format);
    }
    return "format: the driver imports no " + fourccName(drm_fourcc) + " dmabufs (it offers " +
           (offered.empty() ? std::string("none") : offered) + ")";
  }
  return "";
}

namespace {

std::string eglErrorCause(int egl_error) {
  // Codes from EGL 1.5 (egl.h), spelled out to keep this unit free of EGL.
  switch (egl_error) {
    case 0x3009:
      return "the driver refused the format, modifier or plane layout (EGL_BAD_MATCH)";
    case 0x3002:
      return "the driver could not access the buffer (EGL_BAD_ACCESS)";
    case 0x300C:
      return "a plane's file descriptor is not a dmabuf the driver can take, or a value is out of range "
             "(EGL_BAD_PARAMETER)";
    case 0x3004:
      return "the driver does not know an attribute given (EGL_BAD_ATTRIBUTE: the colour-space or siting hints)";
    case 0x3003:
      return "the driver could not make an image of the buffer (EGL_BAD_ALLOC: out of memory, or a buffer it "
             "cannot map)";
    default: {
      char code[16];
      std::snprintf(code, sizeof code, "0x%04x", static_cast<unsigned>(egl_error));
      return std::string("the driver refused the import (EGL error ") + code + ")";
    }
  }
}

}  // namespace

std::string eglImportRefusalCause(int egl_error, const std::vector<DmabufPlaneLayout>& planes) {
  std::string cause = eglErrorCause(egl_error);
  for (std::size_t p = 0; p < planes.size(); ++p) {
    const DmabufPlaneLayout& plane = planes[p];
    cause += "; plane " + std::to_string(p) + "'s dmabuf: ";
    if (plane.buffer_size_bytes)
      cause += std::to_string(*plane.buffer_size_bytes) + " bytes";
    else if (plane.buffer_size_errno != 0)
      cause += "size unknown (lseek: " + std::string(std::strerror(plane.buffer_size_errno)) + ")";
    else
      cause += "size unknown (lseek says 0 bytes)";
    if (!plane.cpu_mapping_errno) continue;
    cause += *plane.cpu_mapping_errno == 0
                 ? ", the CPU maps it"
                 : ", the CPU cannot map it as a software renderer would (mmap: " +
                       std::string(std::strerror(*plane.cpu_mapping_errno)) + ")";
  }
  return cause;
}

}  // namespace probelight::passes
