#include "sim/tag_pattern.hpp"

#include <algorithm>
#include <cstdlib>
#include <memory>

// libapriltag's common/ headers lack extern "C" guards.
extern "C" {
#include <apriltag/apriltag.h>
}

#include "core/apriltag_families.hpp"
#include "sim/scene_config.hpp"

namespace probelight::sim {
namespace {

// The families whose printed image is the plain square grid this printer
// draws (the circle and custom layouts are not).
const char* const kPrintableFamilies[] = {"tag36h11", "tag25h9", "tag16h5", "tagStandard41h12"};

}  // namespace

const std::vector<std::string>& tagFamilyNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> result;
    for (const char* name : kPrintableFamilies) result.emplace_back(name);
    return result;
  }();
  return names;
}

TagPattern::TagPattern(const std::string& family, int id, double tag_size_m) {
  const auto& printable = tagFamilyNames();
  if (std::find(printable.begin(), printable.end(), family) == printable.end())
    throw SceneError("rig.tag_family '" + family + "' is not one the simulator can print");
  if (!(tag_size_m > 0.0)) throw SceneError("rig.tag_size must be positive, got " + std::to_string(tag_size_m));
  AprilTagFamilyHandle tf = createAprilTagFamily(family);
  if (id < 0 || static_cast<uint32_t>(id) >= tf->ncodes)
    throw SceneError("rig.tag_id " + std::to_string(id) + " is outside " + family + "'s 0.." +
                     std::to_string(tf->ncodes - 1));
  image_u8_t* image = apriltag_to_image(tf.get(), id);
  total_cells_ = image->width;
  border_cells_ = tf->width_at_border;
  white_.resize(static_cast<size_t>(total_cells_) * total_cells_);
  for (int row = 0; row < total_cells_; ++row)
    for (int col = 0; col < total_cells_; ++col)
      white_[row * total_cells_ + col] = image->buf[row * image->stride + col] > 127 ? 1 : 0;
  // Debian's libapriltag.so does not export image_u8_destroy; it lives in
  // libapriltag-utils, which CMakeLists links for the simulator.
  image_u8_destroy(image);
  cell_m_ = tag_size_m / border_cells_;
  origin_x_m_ = -total_cells_ * cell_m_ / 2.0;
  origin_y_m_ = total_cells_ * cell_m_ / 2.0;
  reject_beyond_m_ = total_cells_ * cell_m_ * (1.0 + 1e-9);
}

}  // namespace probelight::sim
