// `probelight cameras`: libcamera's cameras, listed (capture/camera_list).
#pragma once

#include <ostream>

#include "app/command_line.hpp"

namespace probelight {

// Prints the listing on `out`; 0, or 1 with one line on `err` when
// libcamera's camera manager does not start.
int runListCameras(const CamerasOptions& options, std::ostream& out, std::ostream& err);

}  // namespace probelight
