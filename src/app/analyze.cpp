#include "app/analyze.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>

#include <GLES2/gl2.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/app_settings.hpp"
#include "stages/bracket_merge.hpp"
#include "core/log_priority.hpp"
#include "stages/post_report.hpp"
#include "stages/stage_settings.hpp"
#include "config/camera_file.hpp"
#include "config/config_reader.hpp"
#include "config/rig_file.hpp"
#include "core/apriltag_families.hpp"
#include "gles/capabilities.hpp"
#include "gles/egl_context.hpp"
#include "ibl/camera_projection.hpp"
#include "ibl/color_transfer.hpp"
#include "gles/render_target.hpp"
#include "ibl/ground_shadow.hpp"
#include "ibl/hdr_bracket.hpp"
#include "ibl/irradiance.hpp"
#include "ibl/probe_to_cube.hpp"
#include "ibl/light_dome.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/probe_outline.hpp"
#include "ibl/post_reference.hpp"
#include "ibl/white_reference.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "passes/ground_shadow.hpp"
#include "passes/object_compositor.hpp"
#include "tracking/probe_edge_fit.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;  // keys in the order written, as the issue lists them

// ball.png: the ball is ~20-60 px across in a 640x480 frame; 4x nearest makes
// each camera pixel a visible block without resampling it.
constexpr int kBallZoom = 4;
constexpr int kBallCropMarginPx = 4;
// The crosses: 128 px tiles hold a 64^2 reflection face as 2x2 blocks and a
// 32^2 diffuse face as 4x4 blocks.
constexpr int kCrossTilePx = 128;

// Colours (BGR) of the overlay: the usual axis colours, and two that stand
// out from both: yellow for the tag, magenta for the ball.
const cv::Scalar kRed(0, 0, 255), kGreen(0, 200, 0), kBlue(255, 64, 0);
const cv::Scalar kTagColour(0, 255, 255), kBallColour(255, 0, 255);

Json vec2Json(const glm::dvec2& v) { return Json::array({v.x, v.y}); }
Json vec3Json(const glm::dvec3& v) { return Json::array({v.x, v.y, v.z}); }

std::string sizeText(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

std::string formatFixed(double value, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << value;
  return out.str();
}

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

// Indented JSON with vectors and matrices on one line each (nlohmann's dump
// puts every number on its own line, 20 lines for a 3x3 rotation).
std::string readableJson(const Json& value, int indent = 0) {
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

struct Analysis {
  Json json = Json::object();
  int status = 0;

  void fail(int exit_status, const std::string& why) {
    status = exit_status;
    json["error"] = why;
  }
};

// One analysis: each method is one step, and each leaves in `result_` what
// it found, so that a failure part-way still reports everything before it.

class Analyzer {
 public:
  Analyzer(const AnalyzeOptions& options, std::ostream& log, const RenderOptions* render = nullptr)
      : options_(options), log_(log), render_(render) {}

  int run() {
    if (const int status = loadInputs(); status != 0) return status;
    frameJson();
    detectTag();
    if (track_.found) measureProbe();
    if (probe_usable_) makeMaps();
    if (reflection_ && !options_.brackets.empty()) mergeBracket();
    if (reflection_) whiteReference();
    if (hdr_reflection_) useHdrMap();
    if (reflection_) fitLights();
    if (render_ && reflection_ && result_.status == 0) renderComposite();
    writePictures();
    return finish();
  }

 private:
  // Every file and flag before any work, each failure one line and status 2.
  int loadInputs() {
    try {
      if (!options_.config_path.empty()) settings_ = loadAppSettings(options_.config_path);
      camera_ = config::loadCameraFile(options_.camera_path);
      rig_ = config::loadRigFile(options_.rig_path);
    } catch (const config::ConfigError& error) {
      return say(2, error.what());
    }
    std::error_code ec;
    if (!fs::exists(options_.frame_path, ec))
      return say(2, options_.frame_path + ": no such file (--frame)");
    frame_bgr_ = cv::imread(options_.frame_path, cv::IMREAD_COLOR);
    if (frame_bgr_.empty()) return say(2, options_.frame_path + ": not a readable image (--frame)");
    if (frame_bgr_.cols != camera_.width_px || frame_bgr_.rows != camera_.height_px)
      // The calibration belongs to another resolution: every pixel position
      // derived from it would be wrong.
      return say(2, options_.frame_path + ": frame is " + sizeText(frame_bgr_.cols, frame_bgr_.rows) + " but " +
                        options_.camera_path + " is " + sizeText(camera_.width_px, camera_.height_px));
    fs::create_directories(options_.out_dir, ec);
    if (ec || !fs::is_directory(options_.out_dir))
      return say(2, options_.out_dir + ": cannot create the output folder (--out)" +
                        (ec ? ": " + ec.message() : std::string()));
    try {
      tracker_ = std::make_unique<tracking::TagTracker>(tagDetectorSettings(settings_, rig_), rig_, camera_);
    } catch (const std::invalid_argument& bad_setting) {
      return say(2, std::string("tracking: ") + bad_setting.what());
    }
    frame_rgb_.resize(frame_bgr_.cols, frame_bgr_.rows);
    cv::Mat rgb(frame_bgr_.rows, frame_bgr_.cols, CV_8UC3, frame_rgb_.pixels.data());
    cv::cvtColor(frame_bgr_, rgb, cv::COLOR_BGR2RGB);
    return 0;
  }

  void frameJson() {
    result_.json["frame"] = {{"path", options_.frame_path},
                             {"width_px", frame_bgr_.cols},
                             {"height_px", frame_bgr_.rows}};
  }

  // Every stage runs twice and the second run is the one timed: a first run
  // pays one-off costs a running kiosk pays once (libapriltag's worker
  // threads and buffers; llvmpipe compiles a shader variant at its first
  // draw, which made probe_to_cube 15.7 ms against 1.3 ms after). The first
  // run's times are kept as timings_first_ms. The two runs give the same
  // result: the tracker forgets its pose history in between, and the maps are
  // replaced, not blended, by the second update.
  void detectTag() {
    std::vector<std::uint8_t> luma;
    for (int run = 0; run < 2; ++run) {
      tracker_->resetHistory();
      const auto start = Clock::now();
      lumaFromRgb(frame_rgb_, luma);
      track_ = tracker_->track(luma.data(), frame_rgb_.width, frame_rgb_.height, frame_rgb_.width);
      timings_[run]["detect_pose"] = msSince(start);
    }
    if (!track_.found) {
      // A single frame has no history, so a tag cut by the frame edge reads
      // as no tag: the message says so.
      std::string message = track_.status;
      if (track_.status_code == tracking::TagTrackStatus::kNoTag)
        message += " (a tag partly outside the frame cannot be found)";
      result_.json["tag"] = {{"status", tracking::toString(track_.status_code)},
                             {"message", message},
                             {"family", rig_.tag_family},
                             {"wanted_id", rig_.tag_id},
                             {"ids_in_view", track_.ids_in_view}};
      result_.fail(kAnalyzeNotFoundExitStatus, "no tag: " + message);
      return;
    }
    Json corners = Json::array();
    for (const glm::dvec2& corner : track_.corners_px) corners.push_back(vec2Json(corner));
    result_.json["tag"] = {{"status", tracking::toString(track_.status_code)},
                           {"message", track_.status},
                           {"family", rig_.tag_family},
                           {"ids_in_view", track_.ids_in_view},
                           {"id", track_.id},
                           {"corners_px", corners},
                           {"decision_margin", track_.decision_margin},
                           {"hamming", track_.hamming}};
    const glm::dmat3& R = track_.pose.R_cam_from_world;  // glm is column-major: R[col][row]
    Json rows = Json::array();
    for (int row = 0; row < 3; ++row) rows.push_back(Json::array({R[0][row], R[1][row], R[2][row]}));
    result_.json["pose"] = {{"R_cam_from_world", rows},
                            {"t_cam_from_world", vec3Json(track_.pose.t_cam_from_world)},
                            {"reprojection_error_px", track_.reprojection_error_px},
                            {"ambiguous", track_.pose_ambiguous}};
  }

  void measureProbe() {
    view_ = ibl::MirrorBallView{camera_, track_.pose, rig_.probe_center_w, rig_.probe_radius_m};
    outline_ = ibl::computeProbeOutline(*view_);
    if (!outline_.valid) {
      result_.fail(kAnalyzeNotFoundExitStatus, "no ball: rig.yaml's ball is not in front of the camera in this pose");
      return;
    }
    if (!outline_.fully_in_image) {
      result_.fail(kAnalyzeNotFoundExitStatus,
                   "ball not fully in the image: its outline spans u " + formatFixed(outline_.min_px.x, 1) + ".." +
                       formatFixed(outline_.max_px.x, 1) + ", v " + formatFixed(outline_.min_px.y, 1) + ".." +
                       formatFixed(outline_.max_px.y, 1) + " px in a " +
                       sizeText(camera_.width_px, camera_.height_px) + " frame");
      return;
    }
    result_.json["probe"] = {{"center_px", vec2Json(outline_.center_px)},
                             {"radius_px", outline_.radius_px},
                             {"bbox_px", Json::array({vec2Json(outline_.min_px), vec2Json(outline_.max_px)})},
                             {"edge_fit", edgeFitJson()}};
    const double min_radius_px = settings_.map_updates.min_probe_radius_px;
    if (outline_.radius_px < min_radius_px) {
      // The run skips such frames too (map_update_policy.hpp): a map from
      // them is mostly magnified pixels.
      result_.fail(kAnalyzeNotFoundExitStatus, "ball too small: radius " + formatFixed(outline_.radius_px, 1) +
                                                   " px, the pipeline needs " + formatFixed(min_radius_px, 1));
      return;
    }
    probe_usable_ = true;
  }

  // The outline refined against the image (tracking/probe_edge_fit.hpp):
  // reported, not used, so that a user can see how far the rig's measured
  // ball is from where the frame shows it (and where in W it would be).
  Json edgeFitJson() {
    std::vector<std::uint8_t> luma;
    lumaFromRgb(frame_rgb_, luma);
    const tracking::ProbeEdgeFit fit =
        tracking::fitProbeOutlineToEdges(luma.data(), frame_rgb_.width, frame_rgb_.height, frame_rgb_.width, outline_,
                                         rig_.probe_reflectance, settings_.maps.stages.camera_transfer);
    Json json = {{"ok", fit.ok}, {"profiles", fit.profiles}, {"trusted_profiles", fit.trusted_profiles}};
    if (!fit.ok) {
      json["reason"] = fit.reason;
      return json;
    }
    json["shift_px"] = vec2Json(fit.shift_px);
    json["radius_scale"] = fit.radius_scale;
    json["center_px"] = vec2Json(fit.center_px);
    json["radius_px"] = fit.radius_px;
    json["rms_px"] = fit.rms_px;
    json["implied_probe_center_w"] =
        vec3Json(tracking::probeCenterForImageShift(track_.pose, camera_, rig_.probe_center_w, fit.shift_px));
    return json;
  }

  void makeMaps() {
    std::string error;
    context_ = gles::EglContext::createHeadless(error);
    if (!context_) {
      result_.fail(1, "GPU: " + error);
      return;
    }
    gles::Capabilities capabilities = gles::probeCapabilities();
    if (settings_.maps.force_8bit) capabilities = capabilities.withoutExtensions();
    result_.json["gl"] = capabilities.summary();
    frame_texture_ = std::make_unique<passes::CameraFrameTexture>();
    maps_ = std::make_unique<passes::EnvironmentMaps>();
    if (!frame_texture_->init(capabilities, error) ||
        !maps_->init(capabilities, environmentMapSettings(settings_), error)) {
      result_.fail(1, "GPU set-up failed: " + error);
      return;
    }
    result_.json["map_storage"] = maps_->storageDescription();
    // Each GPU stage ends with glFinish, as the run does with gpu_finish, so
    // that its time is the GPU's work and not just the queuing. Twice: see
    // detectTag.
    bool blurred = false;
    for (int run = 0; run < 2; ++run) {
      auto start = Clock::now();
      const bool uploaded = frame_texture_->upload(frame_rgb_, error);
      glFinish();
      timings_[run]["upload"] = msSince(start);
      start = Clock::now();
      const bool reflected =
          uploaded && maps_->updateReflection(*frame_texture_, *view_, rig_.probe_reflectance, error);
      glFinish();
      timings_[run]["probe_to_cube"] = msSince(start);
      start = Clock::now();
      blurred = reflected && maps_->updateDiffuse(error);
      glFinish();
      timings_[run]["diffuse_blur"] = msSince(start);
      if (!blurred) break;
    }
    if (blurred) reflection_ = maps_->readReflection(error, &reflection_validity_);
    if (reflection_) diffuse_ = maps_->readDiffuse(error, &diffuse_validity_);
    if (!diffuse_) {
      result_.fail(1, "GPU: " + error);
      return;
    }
    recordIrradiance();
  }

  // E(n) = pi * D(n): the diffuse map holds a cosine-weighted mean radiance,
  // already divided by the ball's reflectance by the probe stage.
  void recordIrradiance() {
    ibl::CubeMapRGB seen(diffuse_->face_size);
    for (int face = 0; face < ibl::kCubeFaceCount; ++face)
      for (size_t i = 0; i < seen.faces[face].size(); ++i)
        seen.faces[face][i] = glm::vec3(diffuse_validity_[face * seen.faces[face].size() + i]);
    Json entries = Json::array();
    for (const glm::dvec3& normal : analysisNormals()) {
      const glm::dvec3 rgb = M_PI * glm::dvec3(diffuse_->sampleBilinear(normal));
      // "seen": the diffuse map's alpha, the share of the directions it
      // gathers that the ball showed; below 1 the blind spot behind the ball
      // is in the footprint.
      entries.push_back({{"normal", vec3Json(normal)},
                         {"rgb", vec3Json(rgb)},
                         {"seen", static_cast<double>(seen.sampleBilinear(normal).x)}});
    }
    result_.json["irradiance"] = entries;
  }

  // --bracket: the frame and its bracket merged into one radiance image
  // (ibl/hdr_bracket.hpp), projected into an HDR reflection map on the CPU.
  // Each bracket frame is checked first and left out, with its reason, when
  // it cannot be read, differs in size, is all clipped or all black, shows
  // the tag elsewhere (the camera moved), or its pixels disagree with its EV
  // by more than half a stop. With nothing left the 8-bit map stands.
  void mergeBracket() {
    const auto start = Clock::now();
    BracketSetup setup{*view_, outline_, rig_, tagDetectorSettings(settings_, rig_),
                       ibl::HdrMergeSettings{settings_.maps.stages.camera_transfer}, reflection_->face_size};
    auto warn = [&](const std::string& path, double ev, const std::string& why) {
      log_ << logPrefix(LogPriority::kWarning) << "probelight: " << (render_ ? "render" : "analyze") << ": warning: "
           << "--bracket " << path << "@" << formatFixed(ev, 1) << " left out: " << why << "\n";
    };
    // Files that cannot be read, or have another size, are left out here;
    // the rest are checked and merged as `run` does its own bracket.
    Json unread = Json::array();
    std::vector<BracketCandidate> candidates;
    for (const BracketOption& bracket : options_.brackets) {
      const cv::Mat bgr = cv::imread(bracket.path, cv::IMREAD_COLOR);
      std::string why;
      std::error_code ec;
      if (bgr.empty())
        why = fs::exists(bracket.path, ec) ? "not a readable image" : "no such file";
      else if (bgr.cols != frame_rgb_.width || bgr.rows != frame_rgb_.height)
        why = "it is " + sizeText(bgr.cols, bgr.rows) + ", --frame is " + sizeText(frame_rgb_.width, frame_rgb_.height);
      if (!why.empty()) {
        unread.push_back({{"frame", bracket.path}, {"ev", bracket.ev}, {"used", false}, {"reason", why}});
        warn(bracket.path, bracket.ev, why);
        continue;
      }
      BracketCandidate candidate{bracket.path, bracket.ev, {}};
      candidate.rgb.resize(bgr.cols, bgr.rows);
      cv::Mat rgb(bgr.rows, bgr.cols, CV_8UC3, candidate.rgb.pixels.data());
      cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
      candidates.push_back(std::move(candidate));
    }
    BracketMergeResult merged = mergeBracketProbe(
        frame_rgb_, std::move(candidates), setup,
        [&](const BracketCandidate& candidate, const std::string& why) { warn(candidate.label, candidate.ev, why); });
    Json frames = unread;
    for (const auto& entry : merged.frames) frames.push_back(Json::parse(entry.dump()));  // json to ordered_json
    Json hdr = {{"frames", frames}};
    if (!merged.hdr_cube) {
      hdr["method"] = "none";
      hdr["status"] = merged.status + ": the 8-bit map stands";
      result_.json["hdr"] = hdr;
      return;  // the white border may still help
    }
    hdr_reflection_ = std::move(merged.hdr_cube);
    hdr["method"] = "bracket";
    hdr["status"] = merged.status;
    hdr["still_clipped_sr"] = merged.still_clipped_sr;
    hdr["ms"] = msSince(start);
    result_.json["hdr"] = hdr;
  }

  // The tag's white border (ibl/white_reference.hpp): read in every frame
  // where the tag was found and reported; without a bracket (and unless
  // --no-white-ref) the light it says the ball's clipped highlights hide
  // is given back to them.
  void whiteReference() {
    const auto start = Clock::now();
    const AprilTagFamilyHandle family = createAprilTagFamily(rig_.tag_family);
    if (!family) return;  // loadRigFile checked the name
    const ibl::WhiteRing ring = ibl::tagWhiteRing(family->width_at_border, family->reversed_border, rig_.tag_size_m);
    ibl::WhiteBorderSettings border_settings;
    border_settings.camera_transfer = settings_.maps.stages.camera_transfer;
    const ibl::RgbPixelReader read_frame = [&](int x, int y) {
      const std::uint8_t* p = frame_rgb_.row(y) + 3 * x;
      return glm::u8vec3(p[0], p[1], p[2]);
    };
    const ibl::WhiteBorderReading reading = ibl::readWhiteBorder(camera_, track_.pose, ring, read_frame, border_settings);
    clipped_mask_ = ibl::clippedTexelMask(*view_, read_frame, border_settings.clip_code, reflection_->face_size);
    Json border = {{"status", ibl::toString(reading.status)},
                   {"message", reading.message},
                   {"tag_white_albedo", rig_.tag_white_albedo},
                   {"patches", reading.patches},
                   {"patches_lit", reading.patches_lit},
                   {"patches_shadowed", reading.patches_shadowed},
                   {"patches_clipped", reading.patches_clipped},
                   {"patches_dark", reading.patches_dark}};
    if (reading.status == ibl::WhiteBorderStatus::kMeasured) border["linear_rgb"] = vec3Json(reading.linear_rgb);
    // What it would add, measured on a copy; used only when nothing better.
    ibl::CubeMapRGB corrected = *reflection_;
    const ibl::WhiteReferenceResult result = ibl::correctClippedWithWhiteBorder(
        corrected, &reflection_validity_, reading, rig_.tag_white_albedo, clipLevel(), &clipped_mask_);
    border["correction"] = {{"status", ibl::toString(result.status)},
                            {"message", result.message},
                            {"border_irradiance_rgb", vec3Json(result.border_irradiance_rgb)},
                            {"ball_irradiance_rgb", vec3Json(result.map_irradiance_rgb)},
                            {"added_radiance_rgb", vec3Json(result.added_radiance_rgb)},
                            {"clipped_upper_sr", result.clipped_upper_sr},
                            {"clipped_lower_sr", result.clipped_lower_sr}};
    // The post divides the border's light between the clipped regions.
    bool post_refined = false;
    if (result.status == ibl::WhiteReferenceStatus::kCorrected && options_.post_reference) {
      ibl::PostReadingSettings post_settings;
      post_settings.camera_transfer = settings_.maps.stages.camera_transfer;
      const ibl::PostCorrection post =
          ibl::correctClippedWithPost(corrected, *reflection_, &reflection_validity_, clipLevel(), &clipped_mask_,
                                      reading, rig_, camera_, track_.pose, read_frame, post_settings);
      border["post"] = postCorrectionJson<Json>(post, rig_);
      post_refined = post.fit.status == ibl::DiffuseFitStatus::kRefined;
      if (post.fit.status == ibl::DiffuseFitStatus::kInconsistent && !hdr_reflection_)
        log_ << logPrefix(LogPriority::kWarning) << "probelight: " << (render_ ? "render" : "analyze")
             << ": warning: the ball's post: " << post.fit.message << "\n";
    }
    border["ms"] = msSince(start);
    Json& hdr = result_.json["hdr"];
    hdr["white_border"] = border;
    if (hdr_reflection_) return;  // a bracket measured the light itself
    const bool usable = result.status == ibl::WhiteReferenceStatus::kCorrected;
    if (!options_.white_reference) {
      hdr["method"] = "none";
      hdr["status"] = "--no-white-ref: the 8-bit map stands";
    } else if (usable) {
      hdr["method"] = post_refined ? "white_border_and_post" : "white_border";
      hdr["status"] = result.message;
      hdr_reflection_ = std::move(corrected);
    } else {
      hdr["method"] = "none";
      hdr["status"] = "white border not used: " + result.message;
      // Only a real problem is worth a warning: nothing clipped needs nothing.
      if (result.status == ibl::WhiteReferenceStatus::kBorderDarker ||
          (result.status == ibl::WhiteReferenceStatus::kBorderUnusable && result.clipped_upper_sr > 0.0))
        log_ << logPrefix(LogPriority::kWarning) << "probelight: " << (render_ ? "render" : "analyze")
             << ": warning: the ball's highlights clip and the tag's white border cannot restore them: "
             << result.message << "\n";
    }
  }

  // Texels at or above this clipped in the camera (the merge's clip code,
  // through the ball's reflectance).
  double clipLevel() const {
    return ibl::clippedMapLevel(ibl::HdrMergeSettings{settings_.maps.stages.camera_transfer}, rig_.probe_reflectance);
  }

  // A bracket or the white border gave light beyond the 8-bit map: the
  // irradiance from it (the 8-bit one kept beside it) and the clipped
  // lights the object's shading adds to the 8-bit diffuse map.
  void useHdrMap() {
    result_.json["irradiance_8bit"] = result_.json["irradiance"];
    Json entries = Json::array();
    for (const Json& old : result_.json["irradiance_8bit"]) {
      const glm::dvec3 normal(old["normal"][0].get<double>(), old["normal"][1].get<double>(), old["normal"][2].get<double>());
      entries.push_back({{"normal", old["normal"]},
                         {"rgb", vec3Json(ibl::irradianceFromCubeMap(*hdr_reflection_, normal))},
                         {"seen", old["seen"]}});
    }
    result_.json["irradiance"] = entries;
    clipped_lights_ = ibl::clippedLights(*hdr_reflection_, *reflection_, &reflection_validity_, clipLevel(),
                                         &clipped_mask_, ibl::SceneLighting::kMaxClippedLights);
    Json lights = Json::array();
    for (const ibl::ClippedLight& light : clipped_lights_)
      lights.push_back({{"direction", vec3Json(light.direction_w)}, {"irradiance_rgb", vec3Json(light.irradiance_rgb)}});
    result_.json["hdr"]["clipped_lights"] = lights;
  }

  // The dome of lights and the dominant light, as `run` fits them at a
  // recalibration, from the reflection map (settings: the `lights` section);
  // from the HDR map when a bracket gave one (nothing in it is clipped).
  void fitLights() {
    const ibl::CubeMapRGB& map = hdr_reflection_ ? *hdr_reflection_ : *reflection_;
    const double clip_level = hdr_reflection_ ? std::numeric_limits<double>::infinity() : 1.0 / rig_.probe_reflectance;
    dome_ = ibl::fitLightDome(map, &reflection_validity_, settings_.lights.dome);
    const ibl::DominantLight dominant =
        ibl::findDominantLight(map, &reflection_validity_, dome_, clip_level, settings_.lights.dome);
    Json lights = Json::array();
    for (const ibl::DomeLight& light : dome_)
      lights.push_back({{"direction", vec3Json(light.direction_w)},
                        {"rgb", vec3Json(light.rgb)},
                        {"spread_deg", glm::degrees(light.spread_rad)}});
    result_.json["lights"] = lights;
    result_.json["light_placement"] = ibl::toString(settings_.lights.dome.placement);
    result_.json["dominant_light"] = {{"direction", vec3Json(dominant.direction_w)},
                                      {"rgb", vec3Json(dominant.rgb)},
                                      {"from_clipped_region", dominant.from_clipped_region}};
  }

  // render: the object, lit by the maps (Lambertian), and its shadow on the
  // real ground, over the frame: the stages `run` draws with.
  void renderComposite() {
    std::string error;
    gles::Capabilities capabilities = gles::probeCapabilities();
    if (settings_.maps.force_8bit) capabilities = capabilities.withoutExtensions();
    ibl::ShadowCaster caster;
    caster.position_w = render_->at_w;
    if (render_->object == "box") {
      caster.shape = ibl::ShadowCaster::Shape::kBox;
      caster.box_size_m = render_->box_size_m;
      caster.box_yaw_rad = glm::radians(render_->yaw_deg);
    } else {
      caster.radius_m = render_->radius_m;
    }
    const std::vector<ibl::ShadowLight> lights = ibl::groundShadowLights(dome_);
    passes::GroundShadow shadow;
    passes::ObjectCompositor compositor;
    gles::RenderTarget target;
    const auto start = Clock::now();
    if (!shadow.init(capabilities, groundShadowSettings(settings_), error) ||
        (settings_.lights.shadows && !shadow.update(lights, caster, error)) ||
        !compositor.init(capabilities, passes::ObjectCompositorSettings{}, maps_->storage(), error) ||
        !target.init(camera_.width_px, camera_.height_px, error)) {
      result_.fail(1, "GPU: " + error);
      return;
    }
    target.bind();
    compositor.drawCameraBackground(*frame_texture_);
    ibl::SurfaceMaterial lambertian;
    lambertian.albedo = glm::vec3(render_->albedo);
    lambertian.k_diffuse = 1.0f;
    bool drawn = shadow.drawOnCameraImage(camera_, track_.pose, *frame_texture_, error);
    // The 8-bit maps as the kiosk keeps them, plus the light they clipped.
    ibl::SceneLighting lighting;
    for (std::size_t k = 0; k < clipped_lights_.size() && k < lighting.clipped_direction_w.size(); ++k) {
      lighting.clipped_direction_w[k] = glm::vec3(clipped_lights_[k].direction_w);
      lighting.clipped_diffuse_rgb[k] = glm::vec3(clipped_lights_[k].irradiance_rgb / 3.14159265358979323846);
    }
    if (drawn && caster.shape == ibl::ShadowCaster::Shape::kSphere)
      drawn = compositor.drawSphereObject(camera_, track_.pose, caster.boundingCentre(), caster.radius_m, lambertian,
                                          lighting, *maps_, error);
    else if (drawn)
      drawn = compositor.drawMeshObject(camera_, track_.pose, passes::boxMesh(caster), lambertian, lighting,
                                        *maps_, error);
    ImageRGB8 composite;
    if (!drawn || !target.readRGB(composite, error)) {
      result_.fail(1, "GPU: " + error);
      return;
    }
    timings_[1]["render"] = timings_[0]["render"] = msSince(start);
    double darkest = 1.0;
    if (shadow.hasShadow())
      if (const auto fraction = shadow.readFraction(error))
        for (const glm::vec3& f : *fraction) darkest = std::min(darkest, static_cast<double>(std::min({f.r, f.g, f.b})));
    Json object = {{"shape", render_->object}, {"at_w", vec2Json(render_->at_w)}, {"albedo", vec3Json(render_->albedo)}};
    if (caster.shape == ibl::ShadowCaster::Shape::kSphere) object["radius_m"] = caster.radius_m;
    else {
      object["size_m"] = vec3Json(caster.box_size_m);
      object["yaw_deg"] = render_->yaw_deg;
    }
    result_.json["render"] = {{"object", object},
                              {"shadow",
                               {{"lights_casting", lights.size()},
                                {"depth_storage", shadow.depthStorageDescription()},
                                {"region_centre_w", vec2Json(shadow.region().centre_w)},
                                {"region_half_size_m", shadow.region().half_size_m},
                                {"darkest_fraction", darkest}}}};
    cv::Mat rgb(composite.height, composite.width, CV_8UC3, composite.pixels.data()), bgr;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    if (save("composite.png", bgr)) result_.json["render"]["composite"] = "composite.png";
  }

  void writePictures() {
    Json pictures = Json::object();
    writeOverlay(pictures);
    if (probe_usable_) writeBallCrop(pictures);
    if (reflection_ && diffuse_) {
      // Values at or above the clip level were white in the camera; the ball
      // divides them by its reflectance.
      const double clip_level = 1.0 / rig_.probe_reflectance;
      writeCross(pictures, "reflection_cross.png", "reflection map", *reflection_, reflection_validity_, clip_level);
      writeCross(pictures, "diffuse_cross.png", "diffuse map", *diffuse_, diffuse_validity_, clip_level);
    }
    result_.json["pictures"] = pictures;
  }

  void writeOverlay(Json& pictures) {
    cv::Mat overlay = frame_bgr_.clone();
    std::string caption;
    if (track_.found) {
      const PoseCamFromWorld& pose = track_.pose;
      std::vector<cv::Point> tag;
      for (const glm::dvec2& corner : track_.corners_px) tag.push_back(toPoint(corner));
      cv::polylines(overlay, tag, true, kTagColour, 1, cv::LINE_AA);
      // The axes are as long as the tag: they reach half a tag beyond its
      // edges, where they cannot be mistaken for the outline. Z goes first and
      // wider: seen from the usual side of the rig Y and Z run up the picture
      // along nearly the same line, and the blue rim keeps Z visible there.
      const double length_m = rig_.tag_size_m;
      struct Axis {
        glm::dvec3 end_w;
        cv::Scalar colour;
        int thickness_px;
        const char* name;
      } axes[] = {{{0, 0, length_m}, kBlue, 4, "Z"}, {{0, length_m, 0}, kGreen, 2, "Y"}, {{length_m, 0, 0}, kRed, 2, "X"}};
      for (const Axis& axis : axes) {
        const std::vector<cv::Point> line = projectSegment(camera_, pose, glm::dvec3(0.0), axis.end_w);
        if (line.size() < 2) continue;
        cv::polylines(overlay, line, false, axis.colour, axis.thickness_px, cv::LINE_AA);
        drawLabel(overlay, axis.name, line.back() + cv::Point(5, 0), 0.5, axis.colour);
      }
      caption = rig_.tag_family + " id " + std::to_string(track_.id);
      if (view_ && outline_.valid) {
        std::vector<cv::Point> ball;
        for (const glm::dvec2& point : outline_.polygon_px) ball.push_back(toPoint(point));
        if (!ball.empty()) cv::polylines(overlay, ball, true, kBallColour, 1, cv::LINE_AA);
        cv::drawMarker(overlay, toPoint(outline_.center_px), kBallColour, cv::MARKER_CROSS, 7, 1);
        caption += "   ball r " + formatFixed(outline_.radius_px, 1) + " px";
      }
    }
    if (result_.json.contains("error")) caption = result_.json["error"].get<std::string>();
    drawCaption(overlay, caption, result_.status == 0 ? cv::Scalar(255, 255, 255) : cv::Scalar(80, 80, 255));
    if (save("overlay.png", overlay))
      pictures["overlay.png"] = {{"shows", "tag outline (yellow), W axes X red, Y green, Z blue (one tag long), "
                                           "ball outline and centre (magenta)"}};
  }

  void writeBallCrop(Json& pictures) {
    const int x0 = std::max(0, static_cast<int>(std::floor(outline_.min_px.x)) - kBallCropMarginPx);
    const int y0 = std::max(0, static_cast<int>(std::floor(outline_.min_px.y)) - kBallCropMarginPx);
    const int x1 = std::min(frame_bgr_.cols, static_cast<int>(std::ceil(outline_.max_px.x)) + kBallCropMarginPx + 1);
    const int y1 = std::min(frame_bgr_.rows, static_cast<int>(std::ceil(outline_.max_px.y)) + kBallCropMarginPx + 1);
    const cv::Rect crop(x0, y0, x1 - x0, y1 - y0);
    cv::Mat enlarged;
    cv::resize(frame_bgr_(crop), enlarged, cv::Size(), kBallZoom, kBallZoom, cv::INTER_NEAREST);
    if (save("ball.png", enlarged))
      pictures["ball.png"] = {{"crop_px", Json::array({crop.x, crop.y, crop.width, crop.height})},
                              {"zoom", kBallZoom}};
  }

  void writeCross(Json& pictures, const std::string& name, const std::string& title, const ibl::CubeMapRGB& map,
                  const std::vector<float>& validity, double clip_level) {
    CrossPictureOptions options;
    options.display_scale = crossDisplayScale(map, validity, clip_level);
    options.tile_px = map.face_size * std::max(1, kCrossTilePx / map.face_size);
    options.title = title;
    options.validity = validity;
    if (save(name, renderCubeCross(map, options)))
      pictures[name] = {{"display_scale", options.display_scale},
                        {"shows", "pixel = sRGB(min(1, linear * display_scale)); faces -X +Y +X -Y in the middle "
                                  "row, +Z above +Y, -Z below it; hatched: not seen by the ball"}};
  }

  bool save(const std::string& name, const cv::Mat& image) {
    const fs::path path = fs::path(options_.out_dir) / name;
    if (cv::imwrite(path.string(), image)) return true;
    result_.fail(1, "cannot write " + path.string());
    return false;
  }

  int finish() {
    for (int run = 0; run < 2; ++run) {
      Json timings = Json::object();
      for (const char* stage : {"detect_pose", "upload", "probe_to_cube", "diffuse_blur", "render"})
        if (timings_[run].count(stage)) timings[stage] = timings_[run][stage];
      result_.json[run == 0 ? "timings_first_ms" : "timings_ms"] = timings;
    }
    // The issue's keys first, then the rest, so the file reads top-down.
    Json ordered = Json::object();
    for (const char* key :
         {"error", "tag", "pose", "probe", "irradiance", "lights", "dominant_light", "render", "timings_ms", "timings_first_ms"})
      if (result_.json.contains(key)) ordered[key] = result_.json[key];
    for (const auto& [key, value] : result_.json.items())
      if (!ordered.contains(key)) ordered[key] = value;
    const fs::path path = fs::path(options_.out_dir) / "analysis.json";
    std::ofstream out(path);
    out << readableJson(ordered) << "\n";
    if (!out) return say(1, "cannot write " + path.string());
    if (result_.status != 0) return say(result_.status, result_.json["error"].get<std::string>());
    return 0;
  }

  using Clock = std::chrono::steady_clock;
  static double msSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  }
  int say(int status, const std::string& message) {
    log_ << logPrefix(status == 0 ? LogPriority::kInfo : LogPriority::kError) << "probelight: "
         << (render_ ? "render" : "analyze") << ": " << message << "\n";
    return status;
  }

  const AnalyzeOptions& options_;
  std::ostream& log_;
  const RenderOptions* render_;  // null for analyze
  std::vector<ibl::DomeLight> dome_;
  AppSettings settings_;
  CameraIntrinsics camera_;
  RigGeometry rig_;
  cv::Mat frame_bgr_;
  ImageRGB8 frame_rgb_;
  std::unique_ptr<tracking::TagTracker> tracker_;
  tracking::TagTrackResult track_;
  std::optional<ibl::MirrorBallView> view_;
  ibl::ProbeOutline outline_;
  bool probe_usable_ = false;
  // The context first, so that it outlives the GL objects declared after it.
  std::unique_ptr<gles::EglContext> context_;
  std::unique_ptr<passes::CameraFrameTexture> frame_texture_;
  std::unique_ptr<passes::EnvironmentMaps> maps_;
  std::optional<ibl::CubeMapRGB> reflection_;
  std::optional<ibl::CubeMapRGB> hdr_reflection_;  // from --bracket, or the 8-bit map corrected by the white border
  std::vector<ibl::ClippedLight> clipped_lights_;
  std::vector<std::uint8_t> clipped_mask_;  // texels holding a clipped ball pixel of --frame  // what hdr_reflection_ holds beyond the 8-bit map's clip
  std::optional<ibl::CubeMapRGB> diffuse_;
  std::vector<float> reflection_validity_;
  std::vector<float> diffuse_validity_;
  std::map<std::string, double> timings_[2];  // first run, second (timed) run
  Analysis result_;
};

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

int runAnalyze(const AnalyzeOptions& options, std::ostream& log) { return Analyzer(options, log).run(); }

int runRender(const RenderOptions& options, std::ostream& log) { return Analyzer(options.frame, log, &options).run(); }

}  // namespace probelight
