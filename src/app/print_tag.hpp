// `probelight print-tag`: the rig's marker as a sheet to print, to scale.
// The tag (rig.yaml's family and id) is drawn from libapriltag's own
// bitmap (sim::TagPattern, as the simulator prints it), its black border's
// outer edge exactly tag_size at the sheet's resolution, on an A4 page when
// it fits (a larger page otherwise), with a 50 mm scale bar and a line
// saying what to measure. The PNG carries its resolution (pHYs), so a print
// at 100% ("actual size", not "fit to page") is to scale.
#pragma once

#include <ostream>
#include <string>

#include "core/types.hpp"

namespace probelight {

struct PrintTagOptions {
  std::string rig_path;  // --rig: the tag's family, id and size (default board/rig.yaml's values)
  std::string out_path;  // --out: the PNG (required)
  int dots_per_inch = 300;
};

// The sheet: white, the tag centred on its upper part, the scale bar and
// the text below. `pixels_per_metre` is what it was drawn at.
ImageRGB8 renderTagSheet(const RigGeometry& rig, int dots_per_inch, double& pixels_per_metre);

// 0: written (a line on `out` says what to measure); 2: a bad rig.yaml or
// flag (one line naming it); 1: the file could not be written.
int runPrintTag(const PrintTagOptions& options, std::ostream& out, std::ostream& err);

}  // namespace probelight
