// Detection on real photos against AprilTag 3's own reference corners.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <regex>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "test_support.hpp"
#include "tracking/tag_detector.hpp"

namespace probelight {
namespace {

using tracking::TagDetection;
using tracking::TagDetector;
using tracking::TagDetectorSettings;

struct ReferenceTag {
  int id = -1;
  std::array<glm::dvec2, 4> corners_apriltag_px;  // AprilTag's order and pixel convention
  double shortestEdgePx() const {
    double shortest = 1e9;
    for (int k = 0; k < 4; ++k)
      shortest = std::min(shortest, glm::length(corners_apriltag_px[(k + 1) % 4] - corners_apriltag_px[k]));
    return shortest;
  }
  glm::dvec2 center() const {
    glm::dvec2 sum(0.0);
    for (const glm::dvec2& c : corners_apriltag_px) sum += c;
    return sum / 4.0;
  }
};

struct Photo {
  std::string name;
  cv::Mat luma;
  std::vector<ReferenceTag> tags;
};

std::vector<Photo> loadPhotos() {
  const char* const kNames[] = {"33369213973_9d9bb4cc96_c", "34085369442_304b6bafd9_c", "34139872896_defdb2f8d9_c"};
  std::vector<Photo> photos;
  const std::regex line_format(R"(^\s*(\d+),\s*\(([-\d.]+) ([-\d.]+)\),\s*\(([-\d.]+) ([-\d.]+)\),\s*\(([-\d.]+) ([-\d.]+)\),\s*\(([-\d.]+) ([-\d.]+)\)\s*$)");
  for (const char* name : kNames) {
    Photo photo;
    photo.name = name;
    std::string base = testing::testDataPath(std::string("apriltag-photos/") + name);
    photo.luma = cv::imread(base + ".jpg", cv::IMREAD_GRAYSCALE);
    std::ifstream list(base + ".txt");
    std::string line;
    std::smatch match;
    while (std::getline(list, line)) {
      if (line.empty()) continue;
      if (!std::regex_match(line, match, line_format)) {
        ADD_FAILURE() << "unparsable reference line in " << base << ".txt: " << line;
        continue;
      }
      ReferenceTag tag;
      tag.id = std::stoi(match[1]);
      for (int k = 0; k < 4; ++k)
        tag.corners_apriltag_px[k] = {std::stod(match[2 + 2 * k]), std::stod(match[3 + 2 * k])};
      photo.tags.push_back(tag);
    }
    photos.push_back(photo);
  }
  return photos;
}

// Worst corner distance between a detection and a reference tag, comparing
// corner k of the reference with the detection's corner for AprilTag corner k.
// A wrong corner order moves corners by a whole tag edge (>= 15 px in these
// photos), far beyond any tolerance used here.
double worstCornerErrorPx(const TagDetection& detection, const ReferenceTag& reference) {
  double worst = 0.0;
  for (int k = 0; k < 4; ++k) {
    glm::dvec2 reference_px = reference.corners_apriltag_px[k] - glm::dvec2(tracking::kAprilTagPixelOffsetPx);
    glm::dvec2 detected_px = detection.corners_px[tracking::kWorldCornerFromAprilTagCorner[k]];
    worst = std::max(worst, glm::length(detected_px - reference_px));
  }
  return worst;
}

struct MatchSummary {
  int reference_count = 0;
  int found = 0;
  std::vector<double> worst_errors_px;  // one per found reference tag
  std::vector<double> shortest_edges_px;
};

// Tags all share id 0, so each reference is matched to the nearest detection centre.
MatchSummary matchAll(const TagDetectorSettings& settings, const std::vector<Photo>& photos, bool report_misses) {
  TagDetector detector(settings);
  MatchSummary summary;
  for (const Photo& photo : photos) {
    std::vector<TagDetection> detections =
        detector.detect(photo.luma.data, photo.luma.cols, photo.luma.rows, static_cast<int>(photo.luma.step));
    for (const ReferenceTag& reference : photo.tags) {
      ++summary.reference_count;
      const TagDetection* nearest = nullptr;
      double nearest_px = 1e9;
      glm::dvec2 reference_center = reference.center() - glm::dvec2(tracking::kAprilTagPixelOffsetPx);
      for (const TagDetection& detection : detections) {
        double distance = glm::length(detection.center_px - reference_center);
        if (detection.id == reference.id && distance < nearest_px) nearest = &detection, nearest_px = distance;
      }
      // A detection of the same tag has its centre within a couple of pixels;
      // neighbouring tags are at least a tag width (>= 15 px) away.
      if (nearest && nearest_px < 5.0) {
        ++summary.found;
        summary.worst_errors_px.push_back(worstCornerErrorPx(*nearest, reference));
        summary.shortest_edges_px.push_back(reference.shortestEdgePx());
      } else if (report_misses) {
        ADD_FAILURE() << photo.name << ": no detection near reference tag at (" << reference_center.x << ", "
                      << reference_center.y << ")";
      }
    }
  }
  return summary;
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

TEST(TagDetectionPhotos, ReferenceSettingsFindAll47TagsWithReferenceCorners) {
  std::vector<Photo> photos = loadPhotos();
  for (const Photo& photo : photos) ASSERT_FALSE(photo.luma.empty()) << photo.name;
  TagDetectorSettings reference_settings;  // what the reference lists were made with
  reference_settings.quad_decimate = 1.0f;
  reference_settings.refine_edges = false;
  MatchSummary summary = matchAll(reference_settings, photos, true);
  EXPECT_EQ(summary.reference_count, 47);
  EXPECT_EQ(summary.found, 47);
  // Same library and settings: only JPEG decoder rounding differs, which moves
  // sub-pixel corners by far less than half a pixel.
  for (std::size_t i = 0; i < summary.worst_errors_px.size(); ++i)
    EXPECT_LT(summary.worst_errors_px[i], 0.5) << "reference tag " << i;
  std::printf("[ reference settings ] found %d/%d, corner error median %.4f px, max %.4f px\n", summary.found,
              summary.reference_count, median(summary.worst_errors_px),
              *std::max_element(summary.worst_errors_px.begin(), summary.worst_errors_px.end()));
}

TEST(TagDetectionPhotos, DefaultSpeedSettingsReport) {
  std::vector<Photo> photos = loadPhotos();
  TagDetectorSettings defaults;
  MatchSummary summary = matchAll(defaults, photos, false);
  int within_half_px = static_cast<int>(std::count_if(summary.worst_errors_px.begin(), summary.worst_errors_px.end(),
                                                      [](double e) { return e < 0.5; }));
  std::printf("[ default settings: decimate %.1f, refine_edges %d ] found %d/%d, %d within 0.5 px of the reference, "
              "corner difference median %.3f px, max %.3f px\n",
              defaults.quad_decimate, defaults.refine_edges, summary.found, summary.reference_count, within_half_px,
              median(summary.worst_errors_px),
              summary.worst_errors_px.empty() ? 0.0 : *std::max_element(summary.worst_errors_px.begin(), summary.worst_errors_px.end()));
  // These tags are 15-45 px across, smaller than the kiosk's (>= 60 px), and
  // decimation loses some of them; those it finds must be the same tags with
  // the same corner order: a corner-order error would be off by a whole edge,
  // sub-pixel refinement differences stay far below a quarter of one.
  ASSERT_GT(summary.found, summary.reference_count / 2);
  for (std::size_t i = 0; i < summary.worst_errors_px.size(); ++i)
    EXPECT_LT(summary.worst_errors_px[i], summary.shortest_edges_px[i] / 4) << "tag " << i;
}

}  // namespace
}  // namespace probelight
