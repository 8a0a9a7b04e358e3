#include "stages/compose_stage.hpp"

#include <algorithm>
#include <numbers>

#include <opencv2/imgproc.hpp>

#include "stages/bloom_bound.hpp"
#include "stages/gpu_stage_timer.hpp"

namespace probelight {

namespace {

// report.json's model.edges: what the GPU gave for the model's edges.
nlohmann::json edgeReport(const passes::ModelUploadStats& stats) {
  return {{"strategy", passes::edgeStrategyName(stats.edges.strategy)},
          {"samples", stats.edges.samples},
          {"grid", stats.edges.grid},
          {"requested_samples", stats.edges.requested_samples},
          {"layer_bytes", stats.edge_layer_bytes},
          {"reason", stats.edges.reason}};
}

}  // namespace

const std::vector<std::uint8_t>& StatusOverlay::render(const std::string& text, int width, int height) {
  if (text == text_ && width == width_ && height == height_) return rgba_;
  text_ = text;
  width_ = width;
  height_ = height;
  cv::Mat canvas(height, width, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  const double scale = std::max(0.4, width / 1280.0);
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
  const int bar_height = size.height + baseline + 12;
  cv::rectangle(canvas, cv::Rect(0, height - bar_height, width, bar_height), cv::Scalar(0, 0, 0, 160), cv::FILLED);
  cv::putText(canvas, text, cv::Point(8, height - baseline - 6), cv::FONT_HERSHEY_SIMPLEX, scale,
              cv::Scalar(255, 255, 255, 255), 1, cv::LINE_AA);
  rgba_.assign(canvas.data, canvas.data + canvas.total() * 4);
  return rgba_;
}

ComposeStage::ComposeStage(const SceneObject& object, const CameraIntrinsics& camera, const RigGeometry& rig,
                           const ibl::CameraTransfer& camera_transfer, RunReport& report, bool finish_gpu)
    : object_(object),
      camera_(camera),
      rig_(rig),
      camera_transfer_(camera_transfer),
      report_(report),
      finish_gpu_(finish_gpu) {
  if (object_.shape.shape == ibl::ShadowCaster::Shape::kBox) mesh_ = passes::boxMesh(object_.shape);
}

Status ComposeStage::init(const gles::Capabilities& capabilities, passes::CubeStorage storage) {
  capabilities_ = capabilities;
  std::string error;
  passes::ObjectCompositorSettings compositor_settings;
  compositor_settings.camera_transfer = camera_transfer_;
  if (!compositor_.init(capabilities, compositor_settings, storage, error))
    return Status::runtimeFailure("GPU set-up failed: " + error);
  if (object_.isModel()) {
    passes::ModelRendererSettings settings;
    settings.edge_samples = passes::kKioskEdgeSamples;
    settings.camera_transfer = camera_transfer_;
    if (!model_renderer_.init(capabilities, storage, *object_.model, object_.world_from_model, settings, error))
      return Status::runtimeFailure("GPU set-up failed for " + object_.model->source + ": " + error);
    // Every display draws the frame into a single-sampled FBO (display/):
    // the layer is made now, so the report says what the GPU gave from the
    // start; each draw checks its framebuffer again.
    if (!model_renderer_.prepareEdges(camera_.width_px, camera_.height_px, 0, error))
      return Status::runtimeFailure("GPU set-up failed for the model's edges: " + error);
    const passes::ModelUploadStats& stats = model_renderer_.stats();
    nlohmann::json& out = report_.extra["model"];
    out["file"] = object_.model->source;
    out["triangles"] = stats.triangles;
    out["draws"] = stats.draw_pieces;
    out["split_for_16_bit_indices"] = stats.split_pieces;
    out["textures"] = stats.textures;
    out["texture_bytes"] = stats.texture_bytes;
    out["vertex_bytes"] = stats.vertex_bytes;
    out["index_bytes"] = stats.index_bytes;
    out["load_ms"] = object_.model->load_ms;
    out["upload_ms"] = stats.upload_ms;
    out["edges"] = edgeReport(stats);
    nlohmann::json warnings = object_.model->warnings;
    for (const std::string& warning : model_renderer_.warnings()) warnings.push_back(warning);
    out["warnings"] = warnings;
  }
  return Status::ok();
}

Status ComposeStage::draw(const tracking::TagTrackResult& track, const std::string& status,
                          const passes::CameraFrameTexture& frame, MapsStage& maps, ShadowsStage& shadows,
                          const ibl::SceneLighting& room_lighting) {
  // The room's lights, and the virtual lamp's when it lights.
  ibl::SceneLighting lighting = room_lighting;
  GpuStageTimer timer(report_, kStageName, finish_gpu_);
  std::string error;
  const bool object_drawn = track.found && maps.haveMaps();
  const bool blurred = object_drawn && (blur_edge_sigma_px_.has_value() || motion_smear_px_.has_value());
  if (blurred) {
    if (!blur_layer_.ready(camera_.width_px, camera_.height_px) &&
        !blur_layer_.init(camera_.width_px, camera_.height_px, camera_transfer_, error))
      return Status::runtimeFailure("GPU set-up failed for the object's blur: " + error);
    if (noise_ != nullptr && !noise_texture_.valid() && !noise_texture_.init(error))
      return Status::runtimeFailure(error);
  }
  // Blurred, the noise goes in after the blur (the layer's composite).
  compositor_.setSensorNoise(blurred ? nullptr : noise_);
  model_renderer_.setSensorNoise(blurred ? nullptr : noise_);
  // The ground: the shadow, with the lamp's light around and over it; the
  // object then covers the part of them under itself.
  PROBELIGHT_TRY(drawGround(object_drawn, track, frame, shadows, lighting));
  if (object_drawn) {
    if (object_.isModel() && shadows.enabled())
      model_renderer_.setSelfShadow(&shadows.pass().selfShadowLights(), shadows.pass().shadowMapSizePx(),
                                    shadows.pass().packedDepth(), &shadows.pass().floorSelfShadows());
    // A model reflects the floor beside it, with its own shadow there.
    if (object_.isModel()) {
      passes::ModelRenderer::NearFloor near_floor;
      near_floor.enabled = true;
      near_floor.ball_centre_w = rig_.probe_center_w;
      near_floor.ball_radius_m = rig_.probe_radius_m;
      near_floor.shadow = shadows.enabled() ? &shadows.pass() : nullptr;
      near_floor.camera_frame = &frame;
      model_renderer_.setNearFloor(near_floor);
    }
    if (blurred) {
      const glm::dvec3 centre = object_.shape.boundingCentre();
      const glm::dvec3 half(object_.shape.boundingRadius());
      const passes::PixelRect region =
          passes::projectedBounds(camera_, track.pose, centre - half, centre + half, 0.01, /*margin_px=*/2);
      // The object's own edges: a pixel's area where they are anti-aliased
      // (a model's layer), none where drawn one sample a pixel.
      const bool antialiased =
          object_.isModel() && model_renderer_.stats().edges.strategy != passes::EdgeStrategy::kOff;
      const double sigma_px =
          blur_edge_sigma_px_ ? passes::objectBlurSigmaPx(*blur_edge_sigma_px_, antialiased ? 1.0 / 12.0 : 0.0) : 0.0;
      blur_layer_.beginObject(region, sigma_px, motion_smear_px_.value_or(glm::dvec2(0.0)));
    }
    const bool drawn = drawObject(track, maps, lighting, error);
    if (!drawn) {
      if (blurred) blur_layer_.restore();
      return Status::runtimeFailure(error);
    }
    if (blurred && !blur_layer_.composite(noise_, noise_ ? &noise_texture_ : nullptr, error))
      return Status::runtimeFailure(error);
    if (object_.isModel()) {
      // A draw into another kind of framebuffer may choose differently.
      nlohmann::json edges = edgeReport(model_renderer_.stats());
      if (nlohmann::json& reported = report_.extra["model"]["edges"]; reported != edges) reported = std::move(edges);
    }
  }
  PROBELIGHT_TRY(drawBloom(object_drawn, track, maps, lighting));
  if (!status.empty()) {
    const auto& rgba = overlay_.render(status, camera_.width_px, camera_.height_px);
    if (!compositor_.drawOverlayRGBA(rgba.data(), camera_.width_px, camera_.height_px, error))
      return Status::runtimeFailure(error);
  }
  return Status::ok();
}

Status ComposeStage::drawGround(bool object_drawn, const tracking::TagTrackResult& track,
                                const passes::CameraFrameTexture& frame, ShadowsStage& shadows,
                                ibl::SceneLighting& lighting) {
  std::string error;
  std::optional<std::string> lamp_skip;
  if (!lamp_config_.enabled) lamp_skip = "off";
  else if (!object_drawn) lamp_skip = "no_object";
  else if (!room_e_up_maps_ || !(ibl::luminance(*room_e_up_maps_) > 0.0)) lamp_skip = "no_room_light";
  if (lamp_skip) {
    report_.recordStageSkip(kLampStageName, *lamp_skip);
    compositor_.drawCameraBackground(frame, exposure_gain_);
    if (object_drawn && !shadows.pass().drawOnCameraImage(camera_, track.pose, frame, error, exposure_gain_))
      return Status::runtimeFailure(error);
    return Status::ok();
  }
  GpuStageTimer timer(report_, kLampStageName, finish_gpu_);
  const ibl::VirtualLamp& lamp = lamp_config_.lamp;
  if (!lamp_ready_) {
    passes::VirtualLampLightSettings settings;
    settings.camera_transfer = camera_transfer_;
    if (!lamp_light_.init(capabilities_, settings, camera_, error))
      return Status::runtimeFailure("GPU set-up failed for the virtual lamp: " + error);
    // The object's triangles, and the rig's real ball and post, which stand
    // in the lamp's light too (the post as a square prism of its width).
    caster_triangles_ = passes::casterTriangles(object_.shape);
    ibl::ShadowCaster ball;
    ball.position_w = glm::dvec2(rig_.probe_center_w);
    ball.radius_m = rig_.probe_radius_m;
    for (glm::vec3 v : passes::casterTriangles(ball)) {
      v.z += static_cast<float>(rig_.probe_center_w.z - rig_.probe_radius_m);
      caster_triangles_.push_back(v);
    }
    if (rig_.post_radius_m > 0.0) {
      ibl::ShadowCaster post;
      post.shape = ibl::ShadowCaster::Shape::kBox;
      post.position_w = glm::dvec2(rig_.probe_center_w);
      post.box_size_m = {2.0 * rig_.post_radius_m, 2.0 * rig_.post_radius_m,
                         rig_.probe_center_w.z - rig_.probe_radius_m};
      const std::vector<glm::vec3> prism = passes::casterTriangles(post);
      caster_triangles_.insert(caster_triangles_.end(), prism.begin(), prism.end());
    }
    lamp_ready_ = true;
  }
  const glm::dvec3 ratio = ibl::lampRatioAtOneMetre(lamp, *room_e_up_maps_);
  // The shadow's mask is made again when the room's colour moves the
  // lamp's ratio by over 2% (a refit). The reach reported: where the lamp
  // still moves a white pixel by half an 8-bit step (ratio 1/510).
  const glm::dvec3 moved = glm::abs(ratio - lamp_sized_for_ratio_);
  if (moved.r > 0.02 * ratio.r || moved.g > 0.02 * ratio.g || moved.b > 0.02 * ratio.b) {
    if (!lamp_light_.updateShadow(lamp, caster_triangles_, error)) return Status::runtimeFailure(error);
    lamp_sized_for_ratio_ = ratio;
    report_.count("virtual_lamp_updates");
    nlohmann::json& out = report_.extra["virtual_lamp"];
    out["reach_m"] = ibl::lampPoolRadiusM(lamp, *room_e_up_maps_, 1.0 / 510.0);
    out["casts_shadow"] = lamp_light_.castsShadow();
    out["ratio_at_one_metre"] = {ratio.r, ratio.g, ratio.b};
  }
  passes::VirtualLampLight::Frame lamp_frame;
  lamp_frame.ratio_at_one_metre_rgb = ratio;
  lamp_frame.dome_shadow = shadows.enabled() ? &shadows.pass() : nullptr;
  lamp_frame.exposure_gain = exposure_gain_;
  // The lamp and the dome's shadow over the frame (the background's and
  // the shadow's draws: the depth alone is cleared), then near the object
  // and the rig everything again.
  compositor_.clearDepth();
  if (!lamp_light_.drawSmooth(camera_, track.pose, frame, rig_, lamp_frame, error) ||
      !lamp_light_.drawDetail(camera_, track.pose, frame, rig_, lamp_frame, error))
    return Status::runtimeFailure(error);
  // The object: the lamp seen from its middle (diffuse E / pi, in the
  // maps' units).
  const glm::dvec3 to_lamp = lamp.position_w - object_.shape.boundingCentre();
  const double d2 = glm::dot(to_lamp, to_lamp);
  const bool lit = d2 > 0.0;
  if (lit) {
    const double spot = ibl::spotWeight(lamp, object_.shape.boundingCentre());
    lighting.lamp_diffuse_rgb = glm::vec3(ratio * *room_e_up_maps_ * (spot / (std::numbers::pi * d2)));
    lighting.lamp_direction_w = glm::vec3(to_lamp / std::sqrt(d2));
  }
  report_.extra["virtual_lamp"]["lights_the_object"] = lit;
  return Status::ok();
}

bool ComposeStage::drawObject(const tracking::TagTrackResult& track, MapsStage& maps,
                              const ibl::SceneLighting& lighting, std::string& error) {
  if (object_.isModel()) return model_renderer_.draw(camera_, track.pose, lighting, maps.maps(), error);
  if (mesh_.empty())
    return compositor_.drawSphereObject(camera_, track.pose, object_.shape.boundingCentre(), object_.shape.radius_m,
                                        object_.material, lighting, maps.maps(), error);
  return compositor_.drawMeshObject(camera_, track.pose, mesh_, object_.material, lighting, maps.maps(), error);
}

Status ComposeStage::drawBloom(bool object_drawn, const tracking::TagTrackResult& track, MapsStage& maps,
                               const ibl::SceneLighting& lighting) {
  if (!bloom_sigma_px_) {
    report_.recordStageSkip(kBloomStageName, "off");
    return Status::ok();
  }
  if (!object_drawn) {
    report_.recordStageSkip(kBloomStageName, "no_object");
    return Status::ok();
  }
  if (!(objectLightBound(object_, lighting, maps.reflectionPeak(), response_gain_rgb_ * exposure_gain_) > 1.0)) {
    report_.recordStageSkip(kBloomStageName, "nothing_above_white");
    return Status::ok();
  }
  const glm::dvec3 centre = object_.shape.boundingCentre();
  const glm::dvec3 half(object_.shape.boundingRadius());
  const passes::PixelRect region = passes::projectedBounds(camera_, track.pose, centre - half, centre + half, 0.01,
                                                           /*margin_px=*/2);
  if (region.empty()) {
    report_.recordStageSkip(kBloomStageName, "not_in_view");
    return Status::ok();
  }
  GpuStageTimer timer(report_, kBloomStageName, finish_gpu_);
  std::string error;
  if (!bloom_.ready(camera_.width_px, camera_.height_px, *bloom_sigma_px_) &&
      !bloom_.init(camera_.width_px, camera_.height_px, *bloom_sigma_px_, camera_transfer_, error))
    return Status::runtimeFailure("GPU set-up failed for the object's bloom: " + error);
  bloom_.beginBrightPass(region);
  compositor_.setBloomBrightPass(true);
  model_renderer_.setBloomBrightPass(true);
  const bool drawn = drawObject(track, maps, lighting, error);
  compositor_.setBloomBrightPass(false);
  model_renderer_.setBloomBrightPass(false);
  if (!drawn) {
    bloom_.restore();
    return Status::runtimeFailure(error);
  }
  if (!bloom_.composite(error)) return Status::runtimeFailure(error);
  return Status::ok();
}

}  // namespace probelight
