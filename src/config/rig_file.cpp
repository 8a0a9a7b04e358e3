#include "config/rig_file.hpp"

#include "core/apriltag_families.hpp"

#include <algorithm>
#include <cmath>

namespace probelight::config {

const std::vector<TagFamilyInfo>& knownTagFamilies() {
  // The id range comes from the library itself, so it cannot drift from the
  // detector's.
  static const std::vector<TagFamilyInfo> families = [] {
    std::vector<TagFamilyInfo> result;
    for (const AprilTagFamilyFactory& factory : aprilTagFamilies()) {
      const AprilTagFamilyHandle family = createAprilTagFamily(factory.name);
      result.push_back({factory.name, static_cast<int>(family->ncodes)});
    }
    return result;
  }();
  return families;
}

namespace {

const TagFamilyInfo* findFamily(const std::string& name) {
  for (const TagFamilyInfo& family : knownTagFamilies())
    if (family.name == name) return &family;
  return nullptr;
}

std::vector<std::string> familyNames() {
  std::vector<std::string> names;
  for (const TagFamilyInfo& family : knownTagFamilies()) names.push_back(family.name);
  return names;
}

}  // namespace

void validateRigGeometry(const RigGeometry& rig, const std::string& path) {
  auto fail = [&](const char* field, const std::string& problem) {
    throw ConfigError(path + ": field '" + field + "': " + problem);
  };
  const TagFamilyInfo* family = findFamily(rig.tag_family);
  if (!family) fail("tag_family", "'" + rig.tag_family + "' is not a family libapriltag ships");
  if (rig.tag_id < 0 || rig.tag_id >= family->code_count)
    fail("tag_id", std::to_string(rig.tag_id) + " is out of range, " + family->name + " has ids 0.." +
                       std::to_string(family->code_count - 1));
  // Lengths from 1 mm to 10 m: a printed tag and a ball on a table, with
  // room either way; beyond them a value is a unit slip (mm for m), and the
  // maths has no reason to meet 1e-300 or 1e308.
  auto inLengthRange = [](double metres) { return metres >= kMinLengthM && metres <= kMaxLengthM; };
  const std::string length_range = "[" + formatNumber(kMinLengthM) + ", " + formatNumber(kMaxLengthM) + "] m";
  if (!inLengthRange(rig.tag_size_m))
    fail("tag_size", formatNumber(rig.tag_size_m) + " is out of range, must be in " + length_range);
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(rig.probe_center_w[i])) fail("probe_center", "must be 3 finite numbers");
  for (int i = 0; i < 3; ++i)
    if (!(std::abs(rig.probe_center_w[i]) <= kMaxLengthM))
      fail("probe_center", formatNumber(rig.probe_center_w[i]) + " is out of range, each must be within +-" +
                               formatNumber(kMaxLengthM) + " m of the tag's centre");
  if (!inLengthRange(rig.probe_radius_m))
    fail("probe_radius", formatNumber(rig.probe_radius_m) + " is out of range, must be in " + length_range);
  // Reflectances and albedos of real surfaces: a tenth of a per cent of the
  // light back would be a black ball, and dividing by it (the maps do) would
  // blow noise up 100 times; 1e-300 overflows a float to inf.
  const std::string fraction_range = "[" + formatNumber(kMinReflectance) + ", 1]";
  if (!(rig.probe_reflectance >= kMinReflectance && rig.probe_reflectance <= 1))
    fail("probe_reflectance", formatNumber(rig.probe_reflectance) + " is out of range, must be in " + fraction_range);
  if (!(rig.tag_white_albedo >= kMinReflectance && rig.tag_white_albedo <= 1))
    fail("tag_white_albedo", formatNumber(rig.tag_white_albedo) + " is out of range, must be in " + fraction_range);
  if (!(rig.post_radius_m >= 0 && rig.post_radius_m < rig.probe_radius_m))
    fail("post_radius", formatNumber(rig.post_radius_m) + " is out of range, must be in [0, probe_radius)");
  if (rig.post_radius_m > 0 && !(rig.probe_center_w.z > rig.probe_radius_m))
    fail("post_radius", "a post is set, but probe_center's z (" + formatNumber(rig.probe_center_w.z) +
                            ") puts the ball on the ground: no post under it (set post_radius to 0)");
  // 0: the post's albedo is not known, so it is no reference.
  if (!(rig.post_albedo == 0 || (rig.post_albedo >= kMinReflectance && rig.post_albedo <= 1)))
    fail("post_albedo", formatNumber(rig.post_albedo) + " is out of range, must be 0 (unknown) or in " + fraction_range);
}

RigGeometry loadRigFile(const std::string& path) {
  ConfigReader file(path);
  RigGeometry rig;
  rig.tag_family = file.readString("tag_family", kRequired, familyNames());
  const TagFamilyInfo* family = findFamily(rig.tag_family);
  rig.tag_id = file.readInt("tag_id", kRequired, Range::closed(0, family->code_count - 1));
  rig.tag_size_m = file.readDouble("tag_size", kRequired, Range::closed(kMinLengthM, kMaxLengthM));
  rig.probe_center_w = file.readVec3("probe_center", kRequired);
  rig.probe_radius_m = file.readDouble("probe_radius", kRequired, Range::closed(kMinLengthM, kMaxLengthM));
  rig.probe_reflectance = file.readDouble("probe_reflectance", 1.0, Range::closed(kMinReflectance, 1.0));
  rig.tag_white_albedo = file.readDouble("tag_white_albedo", 0.85, Range::closed(kMinReflectance, 1.0));
  rig.post_radius_m = file.readDouble("post_radius", 0.0, Range::closed(0.0, 1.0));
  rig.post_albedo = file.readDouble("post_albedo", 0.0, Range::closed(0.0, 1.0));
  file.rejectUnknownFields();
  validateRigGeometry(rig, path);
  return rig;
}

void saveRigFile(const std::string& path, const RigGeometry& rig) {
  validateRigGeometry(rig, path);
  cv::FileStorage storage = openYamlForWriting(path);
  storage.writeComment("probelight rig: the marker and the mirror ball, in the tag's frame W (metres)");
  storage << "tag_family" << rig.tag_family;
  storage << "tag_id" << rig.tag_id;
  storage << "tag_size" << rig.tag_size_m;
  storage << "probe_center" << "[:" << rig.probe_center_w.x << rig.probe_center_w.y << rig.probe_center_w.z << "]";
  storage << "probe_radius" << rig.probe_radius_m;
  storage << "probe_reflectance" << rig.probe_reflectance;
  storage << "tag_white_albedo" << rig.tag_white_albedo;
  storage << "post_radius" << rig.post_radius_m;
  storage << "post_albedo" << rig.post_albedo;
  storage.release();
}

}  // namespace probelight::config
