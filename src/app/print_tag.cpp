#include "app/print_tag.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "capture/rgb_image_io.hpp"
#include "config/config_reader.hpp"
#include "config/rig_file.hpp"
#include "core/log_priority.hpp"
#include "sim/tag_pattern.hpp"

namespace probelight {

namespace {

constexpr double kMetresPerInch = 0.0254;
constexpr double kA4WidthM = 0.210, kA4HeightM = 0.297;
constexpr double kMarginM = 0.015;      // a printer's unprintable edge is 3-5 mm
constexpr double kScaleBarM = 0.050;    // the bar to measure the print against
constexpr double kTextBlockM = 0.045;   // below the tag: the bar and four lines of text

}  // namespace

ImageRGB8 renderTagSheet(const RigGeometry& rig, int dots_per_inch, double& pixels_per_metre) {
  pixels_per_metre = dots_per_inch / kMetresPerInch;
  const sim::TagPattern tag(rig.tag_family, rig.tag_id, rig.tag_size_m);
  const double printed_m = 2.0 * tag.printedHalfSizeM();  // the border and the white ring round it
  const double width_m = std::max(kA4WidthM, printed_m + 2.0 * kMarginM);
  const double height_m = std::max(kA4HeightM, printed_m + kTextBlockM + 3.0 * kMarginM);
  const int width = static_cast<int>(std::lround(width_m * pixels_per_metre));
  const int height = static_cast<int>(std::lround(height_m * pixels_per_metre));
  cv::Mat sheet(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  // The tag: each pixel's centre sampled in W (origin at the tag's centre,
  // +Y up the sheet), the tag centred across and its top a margin down.
  const double centre_x_px = 0.5 * width;
  const double centre_y_px = kMarginM * pixels_per_metre + 0.5 * printed_m * pixels_per_metre;
  const int half_px = static_cast<int>(std::ceil(0.5 * printed_m * pixels_per_metre)) + 1;
  for (int y = std::max(0, static_cast<int>(centre_y_px) - half_px);
       y < std::min(height, static_cast<int>(centre_y_px) + half_px); ++y)
    for (int x = std::max(0, static_cast<int>(centre_x_px) - half_px);
         x < std::min(width, static_cast<int>(centre_x_px) + half_px); ++x) {
      bool white = true;
      const double x_w = (x + 0.5 - centre_x_px) / pixels_per_metre;
      const double y_w = (centre_y_px - (y + 0.5)) / pixels_per_metre;
      if (tag.sample(x_w, y_w, white) && !white) sheet.at<cv::Vec3b>(y, x) = cv::Vec3b(0, 0, 0);
    }
  // The scale bar and what to check, below the tag.
  const int bar_top = static_cast<int>(std::lround(centre_y_px + (0.5 * printed_m + kMarginM) * pixels_per_metre));
  const int bar_left = static_cast<int>(std::lround(kMarginM * pixels_per_metre));
  const int bar_length = static_cast<int>(std::lround(kScaleBarM * pixels_per_metre));
  const int bar_height = std::max(2, static_cast<int>(std::lround(0.002 * pixels_per_metre)));
  cv::rectangle(sheet, cv::Rect(bar_left, bar_top, bar_length, bar_height), cv::Scalar(0, 0, 0), cv::FILLED);
  // Hershey simplex capitals are 22 px tall at scale 1: 2.5 mm capitals.
  const double font_scale = 0.0025 * pixels_per_metre / 22.0;
  const int thickness = std::max(1, static_cast<int>(std::lround(font_scale * 1.5)));
  char line[200];
  const int line_step = static_cast<int>(std::lround(0.008 * pixels_per_metre));
  auto text = [&](int row, const std::string& words) {
    cv::putText(sheet, words, cv::Point(bar_left, bar_top + bar_height + row * line_step), cv::FONT_HERSHEY_SIMPLEX,
                font_scale, cv::Scalar(0, 0, 0), thickness, cv::LINE_AA);
  };
  text(1, "The bar above is 50 mm. Print at 100% (actual size).");
  std::snprintf(line, sizeof line, "%s id %d: the black square is %.1f mm across", rig.tag_family.c_str(), rig.tag_id,
                1000.0 * rig.tag_size_m);
  text(2, line);
  text(3, "Measure it: put what you find in rig.yaml's tag_size.");
  text(4, "Keep the white ring round the black square.");
  ImageRGB8 image;
  image.resize(width, height);
  for (int y = 0; y < height; ++y) std::copy_n(sheet.ptr<std::uint8_t>(y), 3 * width, image.row(y));
  return image;
}

int runPrintTag(const PrintTagOptions& options, std::ostream& out, std::ostream& err) {
  RigGeometry rig;
  try {
    if (!options.rig_path.empty()) rig = config::loadRigFile(options.rig_path);
  } catch (const config::ConfigError& error) {
    err << logPrefix(LogPriority::kError) << "probelight: " << error.what() << "\n";
    return 2;
  }
  double pixels_per_metre = 0.0;
  ImageRGB8 sheet;
  try {
    sheet = renderTagSheet(rig, options.dots_per_inch, pixels_per_metre);
  } catch (const std::exception& error) {  // a family the rig file let through but libapriltag lacks
    err << logPrefix(LogPriority::kError) << "probelight: print-tag: " << error.what() << "\n";
    return 2;
  }
  std::string error;
  if (!writeRgbPng(options.out_path, sheet, error, pixels_per_metre)) {
    err << logPrefix(LogPriority::kError) << "probelight: print-tag: " << error << "\n";
    return 1;
  }
  char line[256];
  std::snprintf(line, sizeof line,
                "%s: %s id %d, %.1f mm across the black border, %d x %d px at %d dpi (%.0f x %.0f mm); print at 100%%\n",
                options.out_path.c_str(), rig.tag_family.c_str(), rig.tag_id, 1000.0 * rig.tag_size_m, sheet.width,
                sheet.height, options.dots_per_inch, 1000.0 * sheet.width / pixels_per_metre,
                1000.0 * sheet.height / pixels_per_metre);
  out << line;
  return 0;
}

}  // namespace probelight
