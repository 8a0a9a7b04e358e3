#include "app/analysis_output.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "app/analyze.hpp"
#include "ibl/camera_projection.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"

namespace probelight {

namespace {

using Json = AnalysisJson;

constexpr int kBallCropMarginPx = 4;

// Colours (BGR) of the overlay: the usual axis colours, and two that stand
// out from both: yellow for the tag, magenta for the ball.
const cv::Scalar kRed(0, 0, 255), kGreen(0, 200, 0), kBlue(255, 64, 0);
const cv::Scalar kTagColour(0, 255, 255), kBallColour(255, 0, 255);

// Texel index along one face axis for a texture coordinate in [0, 1], as GL_NEAREST picks it.
int texelOf(double st, int face_size) {
  return std::clamp(static_cast<int>(std::floor(st * face_size)), 0, face_size - 1);
}

// Text that reads on any background: a dark rim under the light letters.
void drawLabel(cv::Mat& image, const std::string& text, cv::Point origin, double scale,
               const cv::Scalar& colour = cv::Scalar(255, 255, 255)) {
  cv::putText(image, text, origin, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
  cv::putText(image, text, origin, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
}

cv::Point toPoint(const glm::dvec2& p) { return cv::Point(cvRound(p.x), cvRound(p.y)); }

// World points along a segment, projected through the distortion model, so
// that a straight edge in W bends in the picture as it does in the frame.
// Points behind the camera end the polyline.
std::vector<cv::Point> projectSegment(const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                                      const glm::dvec3& from_w, const glm::dvec3& to_w, int steps = 24) {
  std::vector<cv::Point> points;
  for (int i = 0; i <= steps; ++i) {
    const glm::dvec3 p_cam = pose.toCamera(glm::mix(from_w, to_w, static_cast<double>(i) / steps));
    if (p_cam.z <= 1e-6) break;
    points.push_back(toPoint(ibl::projectToPixel(camera, p_cam)));
  }
  return points;
}


// The overlay's caption, on a dark strip across the top, wrapped at spaces
// so that a long reason fits a narrow frame.
void drawCaption(cv::Mat& image, const std::string& text, const cv::Scalar& colour) {
  const double scale = std::max(0.45, image.cols / 1400.0);
  int baseline = 0;
  const int line_px = cv::getTextSize("Ag", cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline).height + baseline + 4;
  std::vector<std::string> lines(1);
  std::istringstream words(text);
  for (std::string word; words >> word;) {
    const std::string longer = lines.back().empty() ? word : lines.back() + " " + word;
    if (!lines.back().empty() &&
        cv::getTextSize(longer, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline).width > image.cols - 12)
      lines.push_back(word);
    else
      lines.back() = longer;
  }
  cv::Mat strip = image(cv::Rect(0, 0, image.cols, std::min(image.rows, line_px * static_cast<int>(lines.size()) + 6)));
  strip *= 0.35;  // darkened, not hidden: the frame stays visible underneath
  for (size_t i = 0; i < lines.size(); ++i)
    cv::putText(image, lines[i], cv::Point(6, static_cast<int>(i + 1) * line_px), cv::FONT_HERSHEY_SIMPLEX, scale,
                colour, 1, cv::LINE_AA);
}

// A value whose items are all numbers, strings, booleans or null, or arrays
// of those: it fits on one line.
bool isFlat(const Json& value) {
  if (!value.is_array()) return !value.is_object();
  return std::all_of(value.begin(), value.end(), [](const Json& item) {
    return item.is_primitive() || (item.is_array() && std::all_of(item.begin(), item.end(),
                                                                  [](const Json& x) { return x.is_primitive(); }));
  });
}

std::string inlineJson(const Json& value) {
  if (!value.is_array()) return value.dump();
  std::string text = "[";
  for (size_t i = 0; i < value.size(); ++i) text += (i ? ", " : "") + inlineJson(value[i]);
  return text + "]";
}

const char* crossTileLabel(CrossTile tile) {
  switch (tile) {
    case CrossTile::kPosX: return "+X (tag right)";
    case CrossTile::kNegX: return "-X";
    case CrossTile::kPosY: return "+Y (tag top)";
    case CrossTile::kNegY: return "-Y";
    case CrossTile::kPosZ: return "+Z (up)";
    case CrossTile::kNegZ: return "-Z (down)";
  }
  return "";
}

}  // namespace

std::string formatFixed(double value, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << value;
  return out.str();
}

// Indented JSON with vectors and matrices on one line each (nlohmann's dump
// puts every number on its own line, 20 lines for a 3x3 rotation).
std::string readableJson(const Json& value, int indent) {
  if (isFlat(value) || value.empty()) return inlineJson(value);
  const std::string pad(static_cast<size_t>(indent + 2), ' ');
  const bool object = value.is_object();
  std::string text = object ? "{\n" : "[\n";
  size_t i = 0;
  for (auto it = value.begin(); it != value.end(); ++it, ++i) {
    text += pad;
    if (object) text += Json(it.key()).dump() + ": ";
    text += readableJson(*it, indent + 2);
    text += i + 1 < value.size() ? ",\n" : "\n";
  }
  return text + std::string(static_cast<size_t>(indent), ' ') + (object ? "}" : "]");
}

std::string overlayCaption(const RigGeometry& rig, const tracking::TagTrackResult& track,
                           const ibl::ProbeOutline* outline) {
  if (!track.found) return "";
  std::string caption = rig.tag_family + " id " + std::to_string(track.id);
  if (outline && outline->valid) caption += "   ball r " + formatFixed(outline->radius_px, 1) + " px";
  return caption;
}

cv::Mat overlayPicture(const cv::Mat& frame_bgr, const CameraIntrinsics& camera, const RigGeometry& rig,
                       const tracking::TagTrackResult& track, const ibl::ProbeOutline* outline,
                       const std::string& caption, bool failed) {
  cv::Mat overlay = frame_bgr.clone();
  if (track.found) {
    std::vector<cv::Point> tag;
    for (const glm::dvec2& corner : track.corners_px) tag.push_back(toPoint(corner));
    cv::polylines(overlay, tag, true, kTagColour, 1, cv::LINE_AA);
    // The axes are as long as the tag: they reach half a tag beyond its
    // edges, where they cannot be mistaken for the outline. Z goes first and
    // wider: seen from the usual side of the rig Y and Z run up the picture
    // along nearly the same line, and the blue rim keeps Z visible there.
    const double length_m = rig.tag_size_m;
    struct Axis {
      glm::dvec3 end_w;
      cv::Scalar colour;
      int thickness_px;
      const char* name;
    } axes[] = {{{0, 0, length_m}, kBlue, 4, "Z"}, {{0, length_m, 0}, kGreen, 2, "Y"}, {{length_m, 0, 0}, kRed, 2, "X"}};
    for (const Axis& axis : axes) {
      const std::vector<cv::Point> line = projectSegment(camera, track.pose, glm::dvec3(0.0), axis.end_w);
      if (line.size() < 2) continue;
      cv::polylines(overlay, line, false, axis.colour, axis.thickness_px, cv::LINE_AA);
      drawLabel(overlay, axis.name, line.back() + cv::Point(5, 0), 0.5, axis.colour);
    }
    if (outline && outline->valid) {
      std::vector<cv::Point> ball;
      for (const glm::dvec2& point : outline->polygon_px) ball.push_back(toPoint(point));
      if (!ball.empty()) cv::polylines(overlay, ball, true, kBallColour, 1, cv::LINE_AA);
      cv::drawMarker(overlay, toPoint(outline->center_px), kBallColour, cv::MARKER_CROSS, 7, 1);
    }
  }
  drawCaption(overlay, caption, failed ? cv::Scalar(80, 80, 255) : cv::Scalar(255, 255, 255));
  return overlay;
}

BallCrop ballCropPicture(const cv::Mat& frame_bgr, const ibl::ProbeOutline& outline) {
  const int x0 = std::max(0, static_cast<int>(std::floor(outline.min_px.x)) - kBallCropMarginPx);
  const int y0 = std::max(0, static_cast<int>(std::floor(outline.min_px.y)) - kBallCropMarginPx);
  const int x1 = std::min(frame_bgr.cols, static_cast<int>(std::ceil(outline.max_px.x)) + kBallCropMarginPx + 1);
  const int y1 = std::min(frame_bgr.rows, static_cast<int>(std::ceil(outline.max_px.y)) + kBallCropMarginPx + 1);
  BallCrop crop;
  crop.crop_px = cv::Rect(x0, y0, x1 - x0, y1 - y0);
  cv::resize(frame_bgr(crop.crop_px), crop.picture, cv::Size(), kBallZoom, kBallZoom, cv::INTER_NEAREST);
  return crop;
}

std::array<glm::dvec3, 14> analysisNormals() {
  std::array<glm::dvec3, 14> normals{glm::dvec3(1, 0, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 1, 0),
                                     glm::dvec3(0, -1, 0), glm::dvec3(0, 0, 1), glm::dvec3(0, 0, -1)};
  size_t next = 6;
  for (const double sx : {1.0, -1.0})
    for (const double sy : {1.0, -1.0})
      for (const double sz : {1.0, -1.0}) normals[next++] = glm::dvec3(sx, sy, sz) / std::sqrt(3.0);
  return normals;
}

cv::Point crossTileCell(CrossTile tile) {
  switch (tile) {
    case CrossTile::kNegX: return {0, 1};
    case CrossTile::kPosY: return {1, 1};
    case CrossTile::kPosX: return {2, 1};
    case CrossTile::kNegY: return {3, 1};
    case CrossTile::kPosZ: return {1, 0};
    case CrossTile::kNegZ: return {1, 2};
  }
  return {0, 0};
}

glm::dvec3 crossTileDirection(CrossTile tile, double a, double c) {
  const glm::dvec3 up(0, 0, 1);
  glm::dvec3 direction;
  switch (tile) {
    // Middle row: facing `forward` with +Z up, the right-hand side is
    // forward x up; the image's downward direction is -Z.
    case CrossTile::kNegX: direction = glm::dvec3(-1, 0, 0) + a * glm::dvec3(0, 1, 0) - c * up; break;
    case CrossTile::kPosY: direction = glm::dvec3(0, 1, 0) + a * glm::dvec3(1, 0, 0) - c * up; break;
    case CrossTile::kPosX: direction = glm::dvec3(1, 0, 0) + a * glm::dvec3(0, -1, 0) - c * up; break;
    case CrossTile::kNegY: direction = glm::dvec3(0, -1, 0) + a * glm::dvec3(-1, 0, 0) - c * up; break;
    // Folded up from the +Y tile: its bottom edge is the ceiling's +Y edge.
    case CrossTile::kPosZ: direction = up + a * glm::dvec3(1, 0, 0) + c * glm::dvec3(0, 1, 0); break;
    // Folded down from the +Y tile: its top edge is the floor's +Y edge.
    case CrossTile::kNegZ: direction = -up + a * glm::dvec3(1, 0, 0) - c * glm::dvec3(0, 1, 0); break;
  }
  return glm::normalize(direction);
}

double crossDisplayScale(const ibl::CubeMapRGB& map, const std::vector<float>& validity, double clip_level) {
  double brightest = 0.0;
  const float unclipped_below = static_cast<float>(0.99 * clip_level);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (size_t i = 0; i < map.faces[face].size(); ++i) {
      if (!validity.empty() && validity[face * map.faces[face].size() + i] < 0.5f) continue;
      const glm::vec3& texel = map.faces[face][i];
      const float channel_max = std::max({texel.r, texel.g, texel.b});
      if (channel_max < unclipped_below) brightest = std::max(brightest, static_cast<double>(channel_max));
    }
  }
  return brightest > 0.0 ? 1.0 / brightest : 1.0 / clip_level;
}

cv::Mat renderCubeCross(const ibl::CubeMapRGB& map, const CrossPictureOptions& options) {
  const int tile = options.tile_px;
  cv::Mat image(3 * tile, 4 * tile, CV_8UC3, cv::Scalar(48, 48, 48));
  const CrossTile tiles[] = {CrossTile::kPosX, CrossTile::kNegX, CrossTile::kPosY,
                             CrossTile::kNegY, CrossTile::kPosZ, CrossTile::kNegZ};
  const int n = map.face_size;
  // sRGB encoding of a byte's worth of linear values, so the loop below does
  // no pow() per pixel.
  std::array<std::uint8_t, 4096> encode{};
  for (size_t i = 0; i < encode.size(); ++i)
    encode[i] = static_cast<std::uint8_t>(std::lround(255.0 * ibl::linearToSrgb(i / double(encode.size() - 1))));
  auto toByte = [&](float linear) {
    const double scaled = std::clamp(linear * options.display_scale, 0.0, 1.0);
    return encode[static_cast<size_t>(std::lround(scaled * (encode.size() - 1)))];
  };
  for (const CrossTile which : tiles) {
    const cv::Point cell = crossTileCell(which);
    for (int y = 0; y < tile; ++y) {
      cv::Vec3b* row = image.ptr<cv::Vec3b>(cell.y * tile + y);
      for (int x = 0; x < tile; ++x) {
        const glm::dvec3 direction =
            crossTileDirection(which, 2.0 * (x + 0.5) / tile - 1.0, 2.0 * (y + 0.5) / tile - 1.0);
        const ibl::CubeTexelCoord coord = ibl::directionToCubeCoord(direction);
        const int tx = texelOf(coord.s, n);
        const int ty = texelOf(coord.t, n);
        const size_t index = static_cast<size_t>(ty) * n + tx;
        const glm::vec3 rgb = map.faces[coord.face][index];
        cv::Vec3b& pixel = row[cell.x * tile + x];
        pixel = cv::Vec3b(toByte(rgb.b), toByte(rgb.g), toByte(rgb.r));
        const bool unseen = !options.validity.empty() && options.validity[coord.face * n * n + index] < 0.5f;
        // Diagonal hatching over what the ball never showed (its blind spot):
        // black there would read as "dark room".
        if (unseen && ((x + y) / 4) % 2 == 0) pixel = cv::Vec3b(90, 0, 90);
      }
    }
  }
  const double text_scale = std::max(0.4, tile / 300.0);
  for (const CrossTile which : tiles) {
    const cv::Point cell = crossTileCell(which);
    cv::rectangle(image, cv::Rect(cell.x * tile, cell.y * tile, tile, tile), cv::Scalar(160, 160, 160), 1);
    drawLabel(image, crossTileLabel(which), cv::Point(cell.x * tile + 5, cell.y * tile + 16), text_scale);
  }
  // The empty top-right cells (two tiles wide) carry the legend, as many
  // lines as fit (small tiles get fewer).
  const int legend_x = 2 * tile + 6;
  const int line_px = static_cast<int>(std::lround(22 * text_scale / 0.4));
  const std::string legend[] = {"shown: sRGB(linear x " + formatFixed(options.display_scale, 2) + ")",
                                "seen from inside the cube:", "-X, +Y, +X, -Y turning right"};
  drawLabel(image, options.title, cv::Point(legend_x, line_px), text_scale * 1.25);
  for (int line = 0; line < 3 && (line + 2) * line_px + 8 < tile; ++line)
    drawLabel(image, legend[line], cv::Point(legend_x, (line + 2) * line_px + 4), text_scale);
  if (!options.validity.empty()) {
    const cv::Point corner(2 * tile, 2 * tile);
    cv::Mat swatch = image(cv::Rect(corner.x + 6, corner.y + 10, 16, 16));
    for (int y = 0; y < swatch.rows; ++y)
      for (int x = 0; x < swatch.cols; ++x)
        swatch.at<cv::Vec3b>(y, x) = ((x + y) / 4) % 2 == 0 ? cv::Vec3b(90, 0, 90) : cv::Vec3b(0, 0, 0);
    drawLabel(image, "not seen by the ball", cv::Point(corner.x + 28, corner.y + 23), text_scale);
  }
  return image;
}

}  // namespace probelight
