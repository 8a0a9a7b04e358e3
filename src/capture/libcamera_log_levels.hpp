// libcamera's log levels as probelight starts it. libcamera 0.4 and later
// log "Could not open any dma-buf provider" as an ERROR on every start
// where none of its dma-buf providers (/dev/dma_heap/*, /dev/udmabuf) opens:
// a laptop, a VM, or a service user without access to them. probelight's
// camera buffers come from the camera's own driver, so the line says
// nothing a user can act on; where a part of libcamera does need one (the
// software ISP), its own failure is logged too. There that category keeps
// only its fatal messages; everything else stays as the user or the
// service's unit set it.
#pragma once

#include <string>

namespace probelight {

// The LIBCAMERA_LOG_LEVELS to use: `current` (null where unset) or else
// `fallback`, with "DmaBufAllocator:FATAL" in front where no provider is
// usable and the setting does not name that category itself. In front, because libcamera 0.4 takes the first pattern that
// matches a category (found by trying both orders).
std::string libcameraLogLevels(const char* current, const std::string& fallback, bool dma_buf_provider_usable);

// Whether one of the providers libcamera 0.4 tries opens for reading and
// writing, as it opens them.
bool dmaBufProviderUsable();

// Sets LIBCAMERA_LOG_LEVELS as above, before a CameraManager starts (its
// logger reads it once).
void setLibcameraLogLevels(const std::string& fallback);

}  // namespace probelight
