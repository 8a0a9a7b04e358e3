#include "tracking/tag_detector.hpp"

#include <cmath>
#include <stdexcept>

#include <apriltag/apriltag.h>

namespace probelight::tracking {

namespace {

// Decoded images smaller than this (after decimation) crash libapriltag 3.3
// (measured: 1-2 px crash, 2x2 decimated survives); no tag fits anyway.
constexpr int kMinimumDecimatedSizePx = 8;

struct DetectionsDeleter {
  void operator()(zarray_t* detections) const { apriltag_detections_destroy(detections); }
};

}  // namespace

std::vector<std::string> availableTagFamilies() {
  std::vector<std::string> names;
  for (const AprilTagFamilyFactory& factory : aprilTagFamilies()) names.emplace_back(factory.name);
  return names;
}

int maxDetectorThreads() {
#ifdef PROBELIGHT_APRILTAG_WORKER_POOL_RACE
  return 1;
#else
  return 16;
#endif
}

const char* aprilTagVersion() { return PROBELIGHT_APRILTAG_VERSION; }

void detail::DetectorDeleter::operator()(apriltag_detector* detector) const {
  if (detector) apriltag_detector_destroy(detector);
}

TagDetector::TagDetector(const TagDetectorSettings& settings) : settings_(settings) {
  if (!findAprilTagFamily(settings.family))
    throw std::invalid_argument("unknown AprilTag family '" + settings.family + "'");
  if (!(settings.quad_decimate >= 1.0f)) throw std::invalid_argument("quad_decimate must be >= 1");
  if (settings.nthreads < 1) throw std::invalid_argument("nthreads must be >= 1");
  if (settings.nthreads > maxDetectorThreads())
    throw std::invalid_argument("nthreads must be <= " + std::to_string(maxDetectorThreads()) +
                                " with this libapriltag (its worker pool races; AprilRobotics/apriltag#339)");
  if (settings.full_frame_every_frames < 1) throw std::invalid_argument("full_frame_every_frames must be >= 1");
  if (!(settings.quad_sigma >= 0.0f)) throw std::invalid_argument("quad_sigma must be >= 0");
  if (!(settings.decode_sharpening >= 0.0)) throw std::invalid_argument("decode_sharpening must be >= 0");

  family_ = createAprilTagFamily(settings.family);
  detector_.reset(apriltag_detector_create());
  if (!family_ || !detector_) throw std::runtime_error("libapriltag could not allocate its detector");
  // Two corrected bits is libapriltag's choice; its lookup table grows with the
  // square of the bit count times the code count, which for the 40k-code
  // families would cost hundreds of MB, so those correct one bit.
  int bits_corrected = family_->ncodes > 5000 ? 1 : 2;
  apriltag_detector_add_family_bits(detector_.get(), family_.get(), bits_corrected);
  detector_->quad_decimate = settings.quad_decimate;
  detector_->nthreads = settings.nthreads;
  detector_->quad_sigma = settings.quad_sigma;
  detector_->refine_edges = settings.refine_edges;
  detector_->decode_sharpening = settings.decode_sharpening;
}

TagDetector::~TagDetector() {
  detector_.reset();  // before the family it borrows
  family_.reset();
}

TagDetector::TagDetector(TagDetector&&) noexcept = default;

TagDetector& TagDetector::operator=(TagDetector&& other) noexcept {
  if (this != &other) {
    detector_.reset();
    family_ = std::move(other.family_);
    detector_ = std::move(other.detector_);
    settings_ = std::move(other.settings_);
  }
  return *this;
}

int TagDetector::minimumFrameSizePx() const {
  return static_cast<int>(std::ceil(kMinimumDecimatedSizePx * settings_.quad_decimate));
}

int TagDetector::borderWidthCells() const { return family_ ? family_->width_at_border : 0; }
int TagDetector::totalWidthCells() const { return family_ ? family_->total_width : 0; }

std::vector<TagDetection> TagDetector::detect(const std::uint8_t* luma, int width, int height, int stride_bytes) {
  std::vector<TagDetection> found;
  if (!luma || !detector_ || stride_bytes < width) return found;
  int minimum_px = minimumFrameSizePx();
  if (width < minimum_px || height < minimum_px) return found;

  // libapriltag only reads the frame (blur and decimation work on copies), so
  // wrapping the caller's plane without copying is safe.
  image_u8_t frame{width, height, stride_bytes, const_cast<std::uint8_t*>(luma)};
  std::unique_ptr<zarray_t, DetectionsDeleter> detections(apriltag_detector_detect(detector_.get(), &frame));
  if (!detections) return found;

  for (int i = 0; i < zarray_size(detections.get()); ++i) {
    apriltag_detection_t* raw = nullptr;
    zarray_get(detections.get(), i, &raw);
    TagDetection detection;
    detection.id = raw->id;
    detection.hamming = raw->hamming;
    detection.decision_margin = raw->decision_margin;
    for (int k = 0; k < 4; ++k) {
      int world_corner = kWorldCornerFromAprilTagCorner[static_cast<std::size_t>(k)];
      detection.corners_px[static_cast<std::size_t>(world_corner)] =
          glm::dvec2(raw->p[k][0] - kAprilTagPixelOffsetPx, raw->p[k][1] - kAprilTagPixelOffsetPx);
    }
    detection.center_px = glm::dvec2(raw->c[0] - kAprilTagPixelOffsetPx, raw->c[1] - kAprilTagPixelOffsetPx);
    found.push_back(detection);
  }
  return found;
}

}  // namespace probelight::tracking
