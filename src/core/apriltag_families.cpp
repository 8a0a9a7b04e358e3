#include "core/apriltag_families.hpp"

extern "C" {
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h10.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagCircle49h12.h>
#include <apriltag/tagCustom48h12.h>
#include <apriltag/tagStandard41h12.h>
#include <apriltag/tagStandard52h13.h>
}

namespace probelight {

const std::vector<AprilTagFamilyFactory>& aprilTagFamilies() {
  static const std::vector<AprilTagFamilyFactory> families = {
      {"tag36h11", tag36h11_create, tag36h11_destroy},
      {"tag36h10", tag36h10_create, tag36h10_destroy},
      {"tag25h9", tag25h9_create, tag25h9_destroy},
      {"tag16h5", tag16h5_create, tag16h5_destroy},
      {"tagCircle21h7", tagCircle21h7_create, tagCircle21h7_destroy},
      {"tagCircle49h12", tagCircle49h12_create, tagCircle49h12_destroy},
      {"tagCustom48h12", tagCustom48h12_create, tagCustom48h12_destroy},
      {"tagStandard41h12", tagStandard41h12_create, tagStandard41h12_destroy},
      {"tagStandard52h13", tagStandard52h13_create, tagStandard52h13_destroy},
  };
  return families;
}

const AprilTagFamilyFactory* findAprilTagFamily(std::string_view name) {
  for (const AprilTagFamilyFactory& family : aprilTagFamilies())
    if (name == family.name) return &family;
  return nullptr;
}

AprilTagFamilyHandle createAprilTagFamily(std::string_view name) {
  const AprilTagFamilyFactory* factory = findAprilTagFamily(name);
  if (!factory) return AprilTagFamilyHandle(nullptr, AprilTagFamilyDeleter{});
  return AprilTagFamilyHandle(factory->create(), AprilTagFamilyDeleter{factory->destroy});
}

}  // namespace probelight
