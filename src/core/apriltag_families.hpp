// The tag families libapriltag ships, by name, with an owning handle. One
// table for the detector, the configuration checks and the simulator's
// printer, so they always agree on what a family name means.
#pragma once

#include <memory>
#include <string_view>
#include <vector>

extern "C" {
#include <apriltag/apriltag.h>
}

namespace probelight {

struct AprilTagFamilyFactory {
  const char* name;  // as libapriltag names it, e.g. "tag36h11"
  apriltag_family_t* (*create)();
  void (*destroy)(apriltag_family_t*);
};

// Every family in libapriltag 3.3, tag36h11 first.
const std::vector<AprilTagFamilyFactory>& aprilTagFamilies();
// Null when libapriltag has no family of that name.
const AprilTagFamilyFactory* findAprilTagFamily(std::string_view name);

struct AprilTagFamilyDeleter {
  void (*destroy)(apriltag_family_t*) = nullptr;
  void operator()(apriltag_family_t* family) const {
    if (family && destroy) destroy(family);
  }
};
using AprilTagFamilyHandle = std::unique_ptr<apriltag_family_t, AprilTagFamilyDeleter>;

// Creates the family; null handle for an unknown name.
AprilTagFamilyHandle createAprilTagFamily(std::string_view name);

}  // namespace probelight
