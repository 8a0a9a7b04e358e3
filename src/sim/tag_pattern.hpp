// The printed AprilTag as an albedo pattern on the ground, from libapriltag's
// own bitmap so the simulator cannot disagree with the detector about codes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace probelight::sim {

class TagPattern {
 public:
  // Throws SceneError naming rig.tag_family / rig.tag_id when unknown.
  TagPattern(const std::string& family, int id, double tag_size_m);

  // Bitmap orientation: apriltag_to_image() row 0 is the top of the printed
  // tag (+Y in W), column 0 its left (-X). The bitmap has total_width cells
  // (10 for tag36h11: a white ring around the 8-cell black border), and
  // tag_size_m spans the width_at_border cells centred on the origin.
  // Returns true and sets is_white when (x_w, y_w) lies on the printed image.
  bool sample(double x_w, double y_w, bool& is_white) const {
    // Most floor points are off the tag: turned away before the divisions
    // (a latency a floor ray waits on), by a test that rejects only points
    // the exact one below rejects too (the margin covers its rounding), and
    // NaN, which would index the bitmap at int(NaN).
    const double right_m = x_w - origin_x_m_, down_m = origin_y_m_ - y_w;
    if (!(right_m >= 0.0 && down_m >= 0.0 && right_m <= reject_beyond_m_ && down_m <= reject_beyond_m_)) return false;
    double col = (x_w - origin_x_m_) / cell_m_;
    double row = (origin_y_m_ - y_w) / cell_m_;
    if (col < 0.0 || row < 0.0 || col >= total_cells_ || row >= total_cells_) return false;
    is_white = white_[static_cast<int>(row) * total_cells_ + static_cast<int>(col)] != 0;
    return true;
  }
  // Half the printed image's edge (border plus white ring), metres.
  double printedHalfSizeM() const { return total_cells_ * cell_m_ / 2.0; }
  int totalCells() const { return total_cells_; }
  int borderCells() const { return border_cells_; }

 private:
  std::vector<std::uint8_t> white_;  // total_cells_^2, row 0 at the top
  int total_cells_ = 0;
  int border_cells_ = 0;
  double cell_m_ = 0.0;
  double origin_x_m_ = 0.0;  // W x of the bitmap's left edge
  double origin_y_m_ = 0.0;  // W y of the bitmap's top edge
  double reject_beyond_m_ = 0.0;  // a little past the printed edge, total_cells_ * cell_m_ * (1 + 1e-9)
};

// Families the simulator can print.
const std::vector<std::string>& tagFamilyNames();

}  // namespace probelight::sim
