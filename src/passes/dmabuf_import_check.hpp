// Why a camera's dmabuf would not import as an EGLImage, in one line a
// person can act on: told before the driver is asked where the buffer and
// the driver's own list say it (a format the driver does not import, a plane
// that does not fit in its buffer), and named from the driver's refusal
// (the EGL error eglCreateImageKHR leaves) where they cannot. Pure: no EGL
// calls, so that each cause has its own test.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace probelight::passes {

// One plane of a frame as the camera hands it over: where it starts in its
// dmabuf, how far apart its rows are, and how much of each row and how many
// rows the format needs.
struct DmabufPlaneLayout {
  std::uint64_t offset_bytes = 0;
  std::int64_t pitch_bytes = 0;
  std::int64_t row_bytes = 0;
  std::int64_t rows = 0;
  // The dmabuf's size, where its file descriptor tells it (lseek to its end).
  std::optional<std::uint64_t> buffer_size_bytes;
  // lseek's errno where it failed (0 where it said 0 bytes or told the size).
  int buffer_size_errno = 0;
  // Asked after a refusal only: whether the CPU could map the whole buffer
  // for reading and writing, as a software renderer (llvmpipe) maps an
  // imported buffer. 0 where it could, else the errno of mmap.
  std::optional<int> cpu_mapping_errno;
};

// "NV12" for DRM's 'NV12' code; characters outside ASCII letters and
// digits as '?'.
std::string fourccName(std::uint32_t drm_fourcc);

// Empty when nothing known stands in the way of importing a frame of
// `drm_fourcc` with these planes. `driver_formats` is the driver's list
// (eglQueryDmaBufFormatsEXT), or nullopt where it has none to give.
std::string dmabufImportObstacle(std::uint32_t drm_fourcc, const std::vector<DmabufPlaneLayout>& planes,
                                 const std::optional<std::vector<std::uint32_t>>& driver_formats);

// The driver's refusal as its cause, from the EGL error code, followed by
// what is known of each plane's buffer: its size and whether the CPU maps it.
std::string eglImportRefusalCause(int egl_error, const std::vector<DmabufPlaneLayout>& planes = {});

}  // namespace probelight::passes
