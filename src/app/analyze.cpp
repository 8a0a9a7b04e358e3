#include "app/analyze.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <ostream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/analysis_output.hpp"
#include "app/app_settings.hpp"
#include "capture/rgb_image_io.hpp"
#include "config/camera_file.hpp"
#include "config/config_reader.hpp"
#include "config/rig_file.hpp"
#include "core/log_priority.hpp"
#include "gles/capabilities.hpp"
#include "gles/egl_context.hpp"
#include "gles/render_target.hpp"
#include "capture/frame_recording.hpp"
#include "ibl/hdr_bracket.hpp"
#include "ibl/irradiance.hpp"
#include "ibl/lighting_fit.hpp"
#include "model/gltf_loader.hpp"
#include "stages/bracket_merge.hpp"
#include "stages/compose_stage.hpp"
#include "stages/frame_context.hpp"
#include "stages/lighting_report.hpp"
#include "stages/maps_stage.hpp"
#include "stages/probe_merge.hpp"
#include "stages/run_report.hpp"
#include "stages/scene_object.hpp"
#include "stages/shadows_stage.hpp"
#include "stages/stage_settings.hpp"
#include "stages/track_stage.hpp"
#include "stages/upload_stage.hpp"

namespace probelight {

namespace {

namespace fs = std::filesystem;
using Json = AnalysisJson;

Json vec2Json(const glm::dvec2& v) { return Json::array({v.x, v.y}); }
const auto vec3 = vec3Json<Json>;

std::string sizeText(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

// One frame through the stages `run` uses (track, maps, the lighting fit,
// and for `render` shadows and compose), with the same settings, each step
// leaving in `json_` what it found, so that a failure part-way still reports
// everything before it.
//
// Every timed stage runs twice and the second run is the one timed: a first
// run pays one-off costs a running kiosk pays once (libapriltag's worker
// threads and buffers; llvmpipe compiles a shader variant at its first draw,
// which made probe_to_cube 15.7 ms against 1.3 ms after). The first run's
// times are kept as timings_first_ms. The two runs give the same result: the
// track stage forgets its history in between, and the second maps are made
// fresh, not blended.
class Analyzer {
 public:
  Analyzer(const AnalyzeOptions& options, std::ostream& log, const RenderOptions* render = nullptr)
      : options_(options), log_(log), render_(render) {}

  Status run() {
    PROBELIGHT_TRY(loadInputs());
    json_["frame"] = {{"path", options_.frame_path}, {"width_px", frame_bgr_.cols}, {"height_px", frame_bgr_.rows}};
    if (frame_.metadata.exposure_us > 0.0) {  // a recorded frame's
      json_["frame"]["exposure_us"] = frame_.metadata.exposure_us;
      json_["frame"]["analogue_gain"] = frame_.metadata.analogue_gain;
    }
    PROBELIGHT_TRY(track());
    if (outcome_.isOk()) measureProbe();
    if (outcome_.isOk()) fail(makeMaps());
    if (reflection_ && !options_.brackets.empty()) mergeBracket();
    if (reflection_ && !options_.more_views.empty() && outcome_.isOk()) fail(mergeViews());
    if (reflection_) fitLights();
    if (render_ && reflection_ && outcome_.isOk()) fail(renderComposite());
    writePictures();
    return finish();
  }

 private:
  // Every file and flag before any work, each failure one line.
  Status loadInputs() {
    try {
      if (!options_.config_path.empty()) settings_ = loadAppSettings(options_.config_path);
      camera_ = config::loadCameraFile(options_.camera_path);
      rig_ = config::loadRigFile(options_.rig_path);
    } catch (const config::ConfigError& error) {
      return Status::badInput(error.what());
    }
    // The command's flags narrow the settings' (both must allow the border).
    settings_.lights.white_reference = settings_.lights.white_reference && options_.white_reference;
    settings_.lights.post_reference = settings_.lights.post_reference && options_.post_reference;
    std::error_code ec;
    if (const std::string unreadable = readFrame(options_.frame_path, frame_, frame_bgr_); !unreadable.empty())
      return Status::badInput(unreadable + " (--frame)");
    if (frame_bgr_.cols != camera_.width_px || frame_bgr_.rows != camera_.height_px)
      // The calibration belongs to another resolution: every pixel position
      // derived from it would be wrong.
      return Status::badInput(options_.frame_path + ": frame is " + sizeText(frame_bgr_.cols, frame_bgr_.rows) +
                              " but " + options_.camera_path + " is " + sizeText(camera_.width_px, camera_.height_px));
    fs::create_directories(options_.out_dir, ec);
    if (ec || !fs::is_directory(options_.out_dir))
      return Status::badInput(options_.out_dir + ": cannot create the output folder (--out)" +
                              (ec ? ": " + ec.message() : std::string()));
    PROBELIGHT_TRY(makeObject());
    track_ = std::make_unique<TrackStage>(settings_, rig_, camera_, report_, /*fit_probe_edges=*/true);
    return track_->init();
  }

  // The object `render` puts in (its flags), or probelight.yaml's for
  // `analyze` (which glossy maps its material needs).
  Status makeObject() {
    if (!render_) return sceneObjectFromConfig(settings_, object_);
    object_ = SceneObject{};
    if (render_->object == "model") {
      std::shared_ptr<const model::MeshModel> model = render_->model;
      if (!model) {
        auto loaded = std::make_shared<model::MeshModel>();
        std::string error;
        if (!model::loadGltfModel(render_->model_path, {}, *loaded, error)) return Status::badInput(error + " (--model)");
        for (const std::string& warning : loaded->warnings) log_ << "probelight: warning: " << warning << "\n";
        model = std::move(loaded);
      }
      object_ = modelSceneObject(std::move(model), {render_->at_w, glm::radians(render_->yaw_deg), render_->scale});
      return Status::ok();
    }
    if (render_->object == "box") {
      object_.shape.shape = ibl::ShadowCaster::Shape::kBox;
      object_.shape.box_size_m = render_->box_size_m;
      object_.shape.box_yaw_rad = glm::radians(render_->yaw_deg);
    } else {
      object_.shape.radius_m = render_->radius_m;
    }
    object_.shape.position_w = render_->at_w;
    object_.material.albedo = glm::vec3(render_->albedo);  // Lambertian
    object_.material.k_diffuse = 1.0f;
    return Status::ok();
  }

  // A single frame has no history, so a tag cut by the frame edge reads as
  // no tag: the message says so.
  Status track() {
    for (int run = 0; run < 2; ++run) {
      track_->reset();
      ctx_ = std::make_unique<FrameContext>(frame_, 0);
      track_->run(*ctx_);
      recordTime(run, TrackStage::kStageName);
    }
    const tracking::TagTrackResult& found = ctx_->track;
    if (!found.found) {
      std::string message = found.status;
      if (found.status_code == tracking::TagTrackStatus::kNoTag)
        message += " (a tag partly outside the frame cannot be found)";
      json_["tag"] = {{"status", tracking::toString(found.status_code)},
                      {"message", message},
                      {"family", rig_.tag_family},
                      {"wanted_id", rig_.tag_id},
                      {"ids_in_view", found.ids_in_view}};
      fail(Status::notFound("no tag: " + message));
      return Status::ok();
    }
    Json corners = Json::array();
    for (const glm::dvec2& corner : found.corners_px) corners.push_back(vec2Json(corner));
    json_["tag"] = {{"status", tracking::toString(found.status_code)},
                    {"message", found.status},
                    {"family", rig_.tag_family},
                    {"ids_in_view", found.ids_in_view},
                    {"id", found.id},
                    {"corners_px", corners},
                    {"decision_margin", found.decision_margin},
                    {"hamming", found.hamming}};
    const glm::dmat3& R = found.pose.R_cam_from_world;  // glm is column-major: R[col][row]
    Json rows = Json::array();
    for (int row = 0; row < 3; ++row) rows.push_back(Json::array({R[0][row], R[1][row], R[2][row]}));
    json_["pose"] = {{"R_cam_from_world", rows},
                     {"t_cam_from_world", vec3(found.pose.t_cam_from_world)},
                     {"reprojection_error_px", found.reprojection_error_px},
                     {"ambiguous", found.pose_ambiguous}};
    return Status::ok();
  }

  void measureProbe() {
    const ibl::ProbeOutline& outline = ctx_->outline;
    if (!outline.valid) {
      fail(Status::notFound("no ball: rig.yaml's ball is not in front of the camera in this pose"));
      return;
    }
    if (!outline.fully_in_image) {
      fail(Status::notFound("ball not fully in the image: its outline spans u " + formatFixed(outline.min_px.x, 1) +
                            ".." + formatFixed(outline.max_px.x, 1) + ", v " + formatFixed(outline.min_px.y, 1) +
                            ".." + formatFixed(outline.max_px.y, 1) + " px in a " +
                            sizeText(camera_.width_px, camera_.height_px) + " frame"));
      return;
    }
    json_["probe"] = {{"center_px", vec2Json(outline.center_px)},
                      {"radius_px", outline.radius_px},
                      {"bbox_px", Json::array({vec2Json(outline.min_px), vec2Json(outline.max_px)})},
                      {"edge_fit", edgeFitJson()}};
    const double min_radius_px = settings_.map_updates.min_probe_radius_px;
    if (outline.radius_px < min_radius_px)
      // The run skips such frames too (map_update_policy.hpp): a map from
      // them is mostly magnified pixels.
      fail(Status::notFound("ball too small: radius " + formatFixed(outline.radius_px, 1) + " px, the pipeline needs " +
                            formatFixed(min_radius_px, 1)));
  }

  // The outline refined against the image (tracking/probe_edge_fit.hpp):
  // reported, not used, so that a user can see how far the rig's measured
  // ball is from where the frame shows it (and where in W it would be).
  Json edgeFitJson() const {
    if (!ctx_->probe_edge_fit) return Json{{"ok", false}, {"reason", "not fitted"}};
    const tracking::ProbeEdgeFit& fit = *ctx_->probe_edge_fit;
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
        vec3(tracking::probeCenterForImageShift(ctx_->track.pose, camera_, rig_.probe_center_w, fit.shift_px));
    return json;
  }

  // The upload and maps stages, as `run` has them (environment_maps in
  // probelight.yaml: sizes, the diffuse method, 8-bit storage), twice.
  Status makeMaps() {
    std::string error;
    context_ = gles::EglContext::createHeadless(error);
    if (!context_) return Status::runtimeFailure("GPU: " + error);
    capabilities_ = gles::probeCapabilities();
    if (settings_.maps.force_8bit) capabilities_ = capabilities_.withoutExtensions();
    json_["gl"] = capabilities_.summary();
    upload_ = std::make_unique<UploadStage>(report_, settings_.gpu_finish);
    // Its views are merged by mergeViews, not frame by frame.
    maps_ = std::make_unique<MapsStage>(settings_, rig_, object_.readsGlossy(glossyExponents(settings_)), false,
                                        report_);
    PROBELIGHT_TRY(upload_->init(capabilities_));
    PROBELIGHT_TRY(maps_->init(capabilities_));
    for (int run = 0; run < 2; ++run) {
      maps_->requestFreshMap();
      PROBELIGHT_TRY(upload_->run(*ctx_));
      PROBELIGHT_TRY(maps_->run(*ctx_, upload_->texture()));
      // The kiosk's maps stage keeps its lighting on such a frame.
      if (!ctx_->maps_updated)
        return Status::notFound(std::string("no maps from this frame: ") + toString(ctx_->map_decision.skip));
      for (const char* stage : {UploadStage::kStageName, MapsStage::kReflectionStageName, maps_->diffuseStageName()})
        recordTime(run, stage);
    }
    json_["map_storage"] = maps_->maps().storageDescription();
    reflection_ = maps_->maps().readReflection(error, &reflection_validity_);
    if (reflection_) diffuse_ = maps_->maps().readDiffuse(error, &diffuse_validity_);
    if (!diffuse_) {
      reflection_.reset();
      return Status::runtimeFailure("GPU: " + error);
    }
    json_["irradiance"] = irradianceJson([&](const glm::dvec3& normal) {
      return std::numbers::pi * glm::dvec3(diffuse_->sampleBilinear(normal));
    });
    return Status::ok();
  }

  // E(n) at analysisNormals(). "seen": the diffuse map's alpha, the share of
  // the directions it gathers that the ball showed; below 1 the blind spot
  // behind the ball is in the footprint.
  template <typename Irradiance>
  Json irradianceJson(const Irradiance& irradiance) const {
    ibl::CubeMapRGB seen(diffuse_->face_size);
    for (int face = 0; face < ibl::kCubeFaceCount; ++face)
      for (size_t i = 0; i < seen.faces[face].size(); ++i)
        seen.faces[face][i] = glm::vec3(diffuse_validity_[face * seen.faces[face].size() + i]);
    Json entries = Json::array();
    for (const glm::dvec3& normal : analysisNormals())
      entries.push_back({{"normal", vec3(normal)},
                         {"rgb", vec3(irradiance(normal))},
                         {"seen", static_cast<double>(seen.sampleBilinear(normal).x)}});
    return entries;
  }

  // --bracket: the frame and its bracket merged into one radiance image
  // (ibl/hdr_bracket.hpp), projected into an HDR reflection map on the CPU,
  // as `run` merges its own. Each bracket frame is checked first and left
  // out, with its reason, when it cannot be read, differs in size, is all
  // clipped or all black, shows the tag elsewhere (the camera moved), or its
  // pixels disagree with its EV by more than half a stop. With nothing left
  // the 8-bit map stands.
  void mergeBracket() {
    const auto start = std::chrono::steady_clock::now();
    const BracketSetup setup{ctx_->view, ctx_->outline, rig_, tagDetectorSettings(settings_, rig_),
                             ibl::HdrMergeSettings{settings_.maps.stages.camera_transfer}, reflection_->face_size};
    Json unread = Json::array();
    std::vector<BracketCandidate> candidates = readBracket(options_.brackets, frame_, unread);
    BracketMergeResult merged =
        mergeBracketProbe(frame_.rgb, std::move(candidates), setup,
                          [&](const BracketCandidate& candidate, const std::string& why) {
                            warnBracket(candidate.label, candidate.ev, why);
                          });
    Json frames = unread;
    for (const auto& entry : merged.frames) frames.push_back(Json::parse(entry.dump()));  // json to ordered_json
    Json& hdr = json_["hdr"];
    hdr = {{"frames", frames}};
    if (!merged.hdr_cube) {
      hdr["method"] = "none";
      hdr["status"] = merged.status + ": the 8-bit map stands";
      return;  // the white border may still help
    }
    bracket_map_ = std::move(merged.hdr_cube);
    bracket_still_clipped_ = std::move(merged.still_clipped);
    hdr["method"] = "bracket";
    hdr["status"] = merged.status;
    hdr["still_clipped_sr"] = merged.still_clipped_sr;
    hdr["ms"] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }

  // --frame given again: every view's ball (its bracket merged when it has
  // one) and the frame around it, merged into one world-aligned probe with
  // the first view's (ibl/probe_accumulator.hpp), in the first view's
  // exposure. The merged probe becomes the maps and, where any view had a
  // bracket, the HDR map the lights are fitted from. A view that cannot be
  // used (unreadable, another size, no tag, ball out of the frame or too
  // small) is left out with its reason, as a bracket frame is.
  Status mergeViews() {
    const auto start = std::chrono::steady_clock::now();
    const ibl::HdrMergeSettings merge{settings_.maps.stages.camera_transfer};
    ProbeMerge probe(settings_.maps.stages.camera_transfer, rig_, reflection_->face_size);
    bool any_bracket = bracket_map_.has_value();
    Json views = Json::array();

    // One view into the probe: its map in its own exposure, scaled to the first's.
    auto addView = [&](const FrameBuffer& frame, const ibl::MirrorBallView& view, const ibl::CubeMapRGB& map,
                       const std::vector<float>& validity, const std::vector<std::uint8_t>* still_clipped,
                       double to_first_exposure, Json& entry) {
      const ProbeViewCounts counts = probe.addView(view, map, &validity, still_clipped, to_first_exposure, &frame);
      entry["texels_seen"] = counts.merge.seen;
      entry["texels_first_seen"] = counts.merge.first;
      entry["texels_merged"] = counts.merge.merged;
      entry["texels_changed"] = counts.merge.changed;
      entry["texels_from_frame_around_ball"] = counts.texels_from_frame_around_ball;
      entry["probe_seen_sphere_fraction"] = probe.accumulator().seenSolidAngleFraction();
    };

    Json first = {{"frame", options_.frame_path}, {"used", true}, {"bracket", bracket_map_.has_value()}};
    addView(frame_, ctx_->view, bracket_map_ ? *bracket_map_ : *reflection_, reflection_validity_,
            bracket_map_ ? &bracket_still_clipped_ : nullptr, 1.0, first);
    views.push_back(first);

    for (std::size_t v = 0; v < options_.more_views.size(); ++v) {
      const AnalyzeView& more = options_.more_views[v];
      Json entry = {{"frame", more.frame_path}};
      auto leaveOut = [&](const std::string& why) {
        entry["used"] = false;
        entry["reason"] = why;
        log_ << logPrefix(LogPriority::kWarning) << "probelight: " << command() << ": warning: --frame "
             << more.frame_path << " left out: " << why << "\n";
        views.push_back(entry);
      };
      FrameBuffer frame;
      cv::Mat bgr;
      if (std::string why = readFrame(more.frame_path, frame, bgr); !why.empty()) {
        leaveOut(why);
        continue;
      }
      if (bgr.cols != frame_bgr_.cols || bgr.rows != frame_bgr_.rows) {
        leaveOut("it is " + sizeText(bgr.cols, bgr.rows) + ", the first --frame is " +
                 sizeText(frame_bgr_.cols, frame_bgr_.rows));
        continue;
      }
      // Its exposure against the first's, where both frames say (recorded
      // frames); image files are taken to share the first's.
      double to_first_exposure = 1.0;
      auto product = [](const FrameMetadata& m) {
        return m.exposure_us * (m.analogue_gain > 0.0 ? m.analogue_gain : 1.0);
      };
      if (frame.metadata.exposure_us > 0.0 && frame_.metadata.exposure_us > 0.0) {
        to_first_exposure = product(frame_.metadata) / product(frame.metadata);
        entry["exposure_vs_first"] = 1.0 / to_first_exposure;
      } else {
        entry["exposure_vs_first"] = "assumed the same (no exposure metadata)";
      }
      track_->reset();
      FrameContext ctx(frame, v + 1);
      track_->run(ctx);
      if (!ctx.track.found) {
        leaveOut("no tag: " + ctx.track.status);
        continue;
      }
      if (!ctx.outline.valid || !ctx.outline.fully_in_image) {
        leaveOut("the ball is not fully in the image");
        continue;
      }
      if (ctx.outline.radius_px < settings_.map_updates.min_probe_radius_px) {
        leaveOut("ball too small: radius " + formatFixed(ctx.outline.radius_px, 1) + " px");
        continue;
      }
      // Its reflection map straight from the pass: the update policy, which
      // holds a moving kiosk's maps still, has no say over still photos.
      PROBELIGHT_TRY(upload_->run(ctx));
      std::string error;
      if (!maps_->maps().updateReflection(upload_->texture(), ctx.view, rig_.probe_reflectance, error))
        return Status::runtimeFailure("GPU: " + error);
      std::vector<float> validity;
      const std::optional<ibl::CubeMapRGB> map = maps_->maps().readReflection(error, &validity);
      if (!map) return Status::runtimeFailure("GPU: " + error);
      entry["used"] = true;
      entry["tag_id"] = ctx.track.id;
      entry["ball_radius_px"] = ctx.outline.radius_px;
      // Its own bracket, merged as the first view's is.
      std::optional<ibl::CubeMapRGB> hdr;
      std::vector<std::uint8_t> still_clipped;
      if (!more.brackets.empty()) {
        const BracketSetup setup{ctx.view, ctx.outline, rig_, tagDetectorSettings(settings_, rig_), merge,
                                 reflection_->face_size};
        Json unread = Json::array();
        std::vector<BracketCandidate> candidates = readBracket(more.brackets, frame, unread);
        BracketMergeResult merged = mergeBracketProbe(
            frame.rgb, std::move(candidates), setup,
            [&](const BracketCandidate& candidate, const std::string& why) { warnBracket(candidate.label, candidate.ev, why); });
        entry["bracket_status"] = merged.status;
        if (!unread.empty()) entry["bracket_unread"] = unread;
        if (merged.hdr_cube) {
          hdr = std::move(merged.hdr_cube);
          still_clipped = std::move(merged.still_clipped);
          any_bracket = true;
        }
      }
      entry["bracket"] = hdr.has_value();
      addView(frame, ctx.view, hdr ? *hdr : *map, validity, hdr ? &still_clipped : nullptr, to_first_exposure, entry);
      views.push_back(entry);
    }

    // The merged probe as the maps: the 8-bit map what the camera shows
    // (clamped at its clip level), the HDR map all of it.
    const std::vector<float> validity = probe.validity();
    reflection_ = probe.liveMap();
    reflection_validity_ = validity;
    if (any_bracket) {
      bracket_map_ = probe.hdrMap();
      bracket_still_clipped_ = probe.accumulator().lowerBounds();
    }
    PROBELIGHT_TRY(maps_->setProbe(*reflection_, validity));
    std::string error;
    diffuse_ = maps_->maps().readDiffuse(error, &diffuse_validity_);
    if (!diffuse_) return Status::runtimeFailure("GPU: " + error);
    json_["irradiance"] = irradianceJson([&](const glm::dvec3& normal) {
      return std::numbers::pi * glm::dvec3(diffuse_->sampleBilinear(normal));
    });
    long used = 0;
    for (const Json& view : views) used += view["used"].get<bool>() ? 1 : 0;
    json_["views"] = {{"given", views.size()},
                      {"used", used},
                      {"probe_seen_sphere_fraction", probe.accumulator().seenSolidAngleFraction()},
                      {"ms", std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count()},
                      {"each", views}};
    return Status::ok();
  }

  // A view's --bracket frames, read: each one that cannot be read, differs
  // in size from its --frame (`base`), or has no EV to be placed by is left
  // out (into `unread`, with its reason, and a warning).
  std::vector<BracketCandidate> readBracket(const std::vector<BracketOption>& brackets, const FrameBuffer& base,
                                            Json& unread) const {
    std::vector<BracketCandidate> candidates;
    for (BracketOption bracket : brackets) {
      FrameBuffer frame;
      cv::Mat bgr;
      std::string why = readFrame(bracket.path, frame, bgr);
      if (why.empty() && (bgr.cols != base.rgb.width || bgr.rows != base.rgb.height))
        why = "it is " + sizeText(bgr.cols, bgr.rows) + ", its --frame is " + sizeText(base.rgb.width, base.rgb.height);
      if (why.empty() && bracket.ev_from_metadata) why = evFromMetadata(frame.metadata, base.metadata, bracket.ev);
      if (!why.empty()) {
        unread.push_back({{"frame", bracket.path}, {"ev", bracket.ev}, {"used", false}, {"reason", why}});
        warnBracket(bracket.path, bracket.ev, why);
        continue;
      }
      candidates.push_back({bracket.path, bracket.ev, std::move(frame.rgb)});
    }
    return candidates;
  }

  // An image file, or a recorded frame (run --record) decoded from the
  // camera's layout as the GPU decodes it (FrameBuffer::toRgb, its CPU
  // reference), its metadata kept. "" when read; otherwise why not, naming
  // the file.
  static std::string readFrame(const std::string& path, FrameBuffer& frame, cv::Mat& bgr) {
    if (isRecordedFramePath(path)) {
      FrameBuffer recorded;
      if (const Status status = readRecordedFrame(path, recorded); !status.isOk()) return status.message();
      frame.rgb = recorded.toRgb();
      frame.metadata = recorded.metadata;
    } else {
      std::string why;
      const cv::Mat read = readImageFile(path, cv::IMREAD_COLOR, &why);
      if (read.empty()) return path + ": " + why;
      frame.rgb = rgbFromBgr(read);
      frame.metadata.origin = path;
    }
    frame.finishRgb();
    bgr = bgrFromRgb(frame.rgb);
    return "";
  }

  // A recorded bracket frame's EV from --frame's: their exposures (time x
  // gain) as the metadata says. Why not, when it cannot be told or is out
  // of --bracket's range.
  static std::string evFromMetadata(const FrameMetadata& bracket, const FrameMetadata& base, double& ev) {
    if (!(bracket.exposure_us > 0.0) || !(base.exposure_us > 0.0))
      return "its metadata or --frame's has no exposure: give it as FILE@EV";
    auto product = [](const FrameMetadata& m) { return m.exposure_us * (m.analogue_gain > 0.0 ? m.analogue_gain : 1.0); };
    ev = std::log2(product(bracket) / product(base));
    if (!(std::abs(ev) >= kMinBracketEv && std::abs(ev) <= kMaxBracketEv))
      return "its exposure is " + formatFixed(ev, 2) + " stops from --frame's (0.125 to 24 either way is a bracket)";
    return "";
  }

  void warnBracket(const std::string& path, double ev, const std::string& why) const {
    log_ << logPrefix(LogPriority::kWarning) << "probelight: " << command() << ": warning: --bracket " << path << "@"
         << formatFixed(ev, 1) << " left out: " << why << "\n";
  }

  // The lighting fit `run` makes at a recalibration (ibl/lighting_fit.hpp:
  // white border, post, clipped lights, dome, dominant light), from the
  // bracket when there is one. The border is read and reported even when
  // a bracket or --no-white-ref leaves it unused, to compare.
  void fitLights() {
    ibl::LightingFitInputs inputs;
    inputs.map_8bit = &*reflection_;
    inputs.validity = &reflection_validity_;
    inputs.hdr_map = bracket_map_ ? &*bracket_map_ : nullptr;
    inputs.view = &ctx_->view;
    inputs.read_pixel = [this](int x, int y) { return frame_.rgbAt(x, y); };
    inputs.rig = rig_;
    inputs.white_ring = tagWhiteRingOf(rig_);
    fit_ = ibl::fitLighting(inputs, lightingFitSettings(settings_));
    for (const std::string& warning : fit_.warnings)
      log_ << logPrefix(LogPriority::kWarning) << "probelight: " << command() << ": warning: " << warning << "\n";
    // ordered_json keeps its keys in a vector: a reference into it does not
    // survive an insertion, so "hdr" is looked up each time.
    Json hdr = json_.contains("hdr") ? json_["hdr"] : Json::object();
    if (fit_.border) {
      Json border = whiteBorderAnalysisJson(*fit_.border, *fit_.border_correction, rig_.tag_white_albedo);
      if (fit_.post) border["post"] = postCorrectionJson<Json>(*fit_.post, rig_);
      border["ms"] = fit_.border_ms;
      hdr["white_border"] = border;
    }
    if (fit_.method != ibl::LightingFitMethod::kBracket) {
      hdr["method"] = ibl::toString(fit_.method);
      if (fit_.method != ibl::LightingFitMethod::kEightBit)
        hdr["status"] = fit_.border_correction->message;
      else if (!options_.white_reference)
        hdr["status"] = "--no-white-ref: the 8-bit map stands";
      else if (!settings_.lights.white_reference)
        hdr["status"] = "lights.white_reference is off: the 8-bit map stands";
      else if (fit_.border_correction)
        hdr["status"] = "white border not used: " + fit_.border_correction->message;
    }
    if (fit_.fitted_map) {
      // Light beyond the 8-bit map: the irradiance from it (the 8-bit one
      // kept beside it), and the clipped lights the object's shading adds
      // to the 8-bit diffuse map.
      json_["irradiance_8bit"] = json_["irradiance"];
      json_["irradiance"] = irradianceJson(
          [&](const glm::dvec3& normal) { return ibl::irradianceFromCubeMap(*fit_.fitted_map, normal); });
      hdr["clipped_lights"] = clippedLightsJson<Json>(fit_.clipped_lights);
    }
    json_["hdr"] = hdr;
    json_["lights"] = domeLightsJson<Json>(fit_.dome);
    json_["light_placement"] = ibl::toString(settings_.lights.dome.placement);
    json_["dominant_light"] = dominantLightJson<Json>(fit_.dominant);
  }

  // render: the object, lit by the maps, and its shadow on the real ground,
  // over the frame: the shadows and compose stages `run` draws with.
  Status renderComposite() {
    const SceneObject& object = object_;
    ShadowsStage shadows(settings_, object.shape, report_);
    ComposeStage compose(object, camera_, rig_, settings_.maps.stages.camera_transfer, report_, settings_.gpu_finish);
    gles::RenderTarget target;
    std::string error;
    // The 8-bit maps as the kiosk keeps them, plus the light they clipped.
    ibl::SceneLighting lighting;
    ibl::setClippedLights(lighting, fit_.clipped_lights);
    PROBELIGHT_TRY(shadows.init(capabilities_));
    PROBELIGHT_TRY(compose.init(capabilities_, maps_->maps().storage()));
    PROBELIGHT_TRY(shadows.run(0, fit_.dome, fit_.dome.size()));
    if (!target.init(camera_.width_px, camera_.height_px, error)) return Status::runtimeFailure("GPU: " + error);
    target.bind();
    PROBELIGHT_TRY(compose.draw(ctx_->track, "", upload_->texture(), *maps_, shadows, lighting));
    ImageRGB8 composite;
    if (!target.readRGB(composite, error)) return Status::runtimeFailure("GPU: " + error);
    // Drawn once: the same time in both.
    for (int run = 0; run < 2; ++run)
      for (const char* stage : {ShadowsStage::kStageName, ComposeStage::kStageName}) recordTime(run, stage);
    double darkest = 1.0;
    if (shadows.pass().hasShadow())
      if (const auto fraction = shadows.pass().readFraction(error))
        for (const glm::vec3& f : *fraction) darkest = std::min(darkest, static_cast<double>(std::min({f.r, f.g, f.b})));
    Json shape = {{"shape", render_->object}, {"at_w", vec2Json(render_->at_w)}};
    if (object.isModel()) {
      shape["file"] = object.model->source;
      shape["triangles"] = object.model->triangleCount();
      shape["scale"] = render_->scale;
      shape["yaw_deg"] = render_->yaw_deg;
      shape["load_ms"] = object.model->load_ms;
      shape["bounding_radius_m"] = object.shape.mesh_radius_m;
      if (report_.extra.contains("model")) shape["renderer"] = report_.extra["model"];
    } else if (object.shape.shape == ibl::ShadowCaster::Shape::kSphere) {
      shape["albedo"] = vec3(render_->albedo);
      shape["radius_m"] = object.shape.radius_m;
    } else {
      shape["albedo"] = vec3(render_->albedo);
      shape["size_m"] = vec3(object.shape.box_size_m);
      shape["yaw_deg"] = render_->yaw_deg;
    }
    json_["render"] = {{"object", shape},
                       {"shadow",
                        {{"lights_casting", shadows.lightsCasting()},
                         {"depth_storage", shadows.enabled() ? shadows.pass().depthStorageDescription() : ""},
                         {"region_centre_w", vec2Json(shadows.pass().region().centre_w)},
                         {"region_half_size_m", shadows.pass().region().half_size_m},
                         {"darkest_fraction", darkest}}}};
    if (save("composite.png", bgrFromRgb(composite))) json_["render"]["composite"] = "composite.png";
    return Status::ok();
  }

  void writePictures() {
    Json pictures = Json::object();
    const ibl::ProbeOutline* outline = ctx_ && ctx_->track.found ? &ctx_->outline : nullptr;
    const std::string caption =
        json_.contains("error") ? json_["error"].get<std::string>() : overlayCaption(rig_, ctx_->track, outline);
    if (save("overlay.png", overlayPicture(frame_bgr_, camera_, rig_, ctx_->track, outline, caption, !outcome_.isOk())))
      pictures["overlay.png"] = {{"shows", "tag outline (yellow), W axes X red, Y green, Z blue (one tag long), "
                                           "ball outline and centre (magenta)"}};
    if (json_.contains("probe")) {
      const BallCrop crop = ballCropPicture(frame_bgr_, ctx_->outline);
      if (save("ball.png", crop.picture))
        pictures["ball.png"] = {
            {"crop_px", Json::array({crop.crop_px.x, crop.crop_px.y, crop.crop_px.width, crop.crop_px.height})},
            {"zoom", kBallZoom}};
    }
    if (reflection_ && diffuse_) {
      // Values at or above the clip level were white in the camera; the ball
      // divides them by its reflectance.
      const double clip_level = 1.0 / rig_.probe_reflectance;
      writeCross(pictures, "reflection_cross.png", "reflection map", *reflection_, reflection_validity_, clip_level);
      writeCross(pictures, "diffuse_cross.png", "diffuse map", *diffuse_, diffuse_validity_, clip_level);
    }
    json_["pictures"] = pictures;
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
    fail(Status::runtimeFailure("cannot write " + path.string()));
    return false;
  }

  Status finish() {
    for (int run = 0; run < 2; ++run) {
      json_[run == 0 ? "timings_first_ms" : "timings_ms"] = timings_[run];
    }
    // The issue's keys first, then the rest, so the file reads top-down.
    Json ordered = Json::object();
    for (const char* key :
         {"error", "tag", "pose", "probe", "irradiance", "lights", "dominant_light", "render", "timings_ms", "timings_first_ms"})
      if (json_.contains(key)) ordered[key] = json_[key];
    for (const auto& [key, value] : json_.items())
      if (!ordered.contains(key)) ordered[key] = value;
    const fs::path path = fs::path(options_.out_dir) / "analysis.json";
    std::ofstream out(path);
    out << readableJson(ordered) << "\n";
    if (!out) return Status::runtimeFailure("cannot write " + path.string());
    return outcome_;
  }

  // The first failure is the outcome; what came before it is still written.
  void fail(const Status& status) {
    if (status.isOk() || !outcome_.isOk()) return;
    outcome_ = status;
    json_["error"] = status.message();
  }

  // The stage's last time (ms) as run `run`'s (none when it did not run).
  void recordTime(int run, const char* stage) {
    if (const SampleSeries* times = report_.stage(stage)) timings_[run][stage] = times->latest();
  }

  const char* command() const { return render_ ? "render" : "analyze"; }

  const AnalyzeOptions& options_;
  std::ostream& log_;
  const RenderOptions* render_;  // null for analyze
  SceneObject object_;           // what render puts in (analyze: probelight.yaml's)
  AppSettings settings_;
  CameraIntrinsics camera_;
  RigGeometry rig_;
  cv::Mat frame_bgr_;
  FrameBuffer frame_;
  Json json_ = Json::object();
  Status outcome_;
  RunReport report_;    // the stages' counters and times
  Json timings_[2] = {Json::object(), Json::object()};  // the stages' times: first run, second (timed) run
  std::unique_ptr<TrackStage> track_;
  std::unique_ptr<FrameContext> ctx_;
  // The context first, so that it outlives the GL objects declared after it.
  std::unique_ptr<gles::EglContext> context_;
  gles::Capabilities capabilities_;
  std::unique_ptr<UploadStage> upload_;
  std::unique_ptr<MapsStage> maps_;
  std::optional<ibl::CubeMapRGB> reflection_, diffuse_;
  std::vector<float> reflection_validity_, diffuse_validity_;
  std::optional<ibl::CubeMapRGB> bracket_map_;  // from --bracket
  std::vector<std::uint8_t> bracket_still_clipped_;  // its texels clipped in every exposure
  ibl::LightingFit fit_;
};

}  // namespace

Status runAnalyze(const AnalyzeOptions& options, std::ostream& log) { return Analyzer(options, log).run(); }

Status runRender(const RenderOptions& options, std::ostream& log) { return Analyzer(options.frame, log, &options).run(); }

}  // namespace probelight
