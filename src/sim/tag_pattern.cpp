#include "sim/tag_pattern.hpp"

#include <cstdlib>
#include <memory>

// libapriltag's common/ headers lack extern "C" guards.
extern "C" {
#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagStandard41h12.h>
}

#include "sim/scene_config.hpp"

namespace probelight::sim {
namespace {

struct FamilyFactory {
  const char* name;
  apriltag_family_t* (*create)();
  void (*destroy)(apriltag_family_t*);
};

const FamilyFactory kFamilies[] = {
    {"tag36h11", tag36h11_create, tag36h11_destroy},
    {"tag25h9", tag25h9_create, tag25h9_destroy},
    {"tag16h5", tag16h5_create, tag16h5_destroy},
    {"tagStandard41h12", tagStandard41h12_create, tagStandard41h12_destroy},
};

}  // namespace

const std::vector<std::string>& tagFamilyNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> result;
    for (const FamilyFactory& f : kFamilies) result.emplace_back(f.name);
    return result;
  }();
  return names;
}

TagPattern::TagPattern(const std::string& family, int id, double tag_size_m) {
  const FamilyFactory* factory = nullptr;
  for (const FamilyFactory& f : kFamilies)
    if (family == f.name) factory = &f;
  if (!factory) throw SceneError("rig.tag_family '" + family + "' is not one the simulator can print");
  if (!(tag_size_m > 0.0)) throw SceneError("rig.tag_size must be positive, got " + std::to_string(tag_size_m));
  std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> tf(factory->create(), factory->destroy);
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
}

}  // namespace probelight::sim
