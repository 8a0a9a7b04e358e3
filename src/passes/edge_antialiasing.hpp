// Anti-aliased edges for the virtual model against the camera video (issue
// 16). A model drawn straight into the frame takes one sample a pixel: its
// silhouette is a staircase with the video, the edge error up to the whole
// step between the two. Three ways out, the first the GPU offers:
//
//  - kMultisampleConfig: the framebuffer being drawn into is already
//    multisampled (an EGL config with EGL_SAMPLES > 0 drawn directly, or a
//    caller's multisampled FBO): the model is drawn into it as it is.
//  - kMultisampleRenderToTexture: GL_EXT_multisampled_render_to_texture.
//    The model is drawn into a frame-sized RGBA8 layer with N samples that
//    the GPU resolves into a single-sampled texture as it leaves tile
//    memory, then composited over the video. The fragment shader runs once
//    a pixel; only coverage and depth are per sample.
//  - kOrderedGridSupersampling: core GLES2, the fallback that always works
//    (and what llvmpipe takes: Mesa 22.3 does not list the EXT). The model is
//    drawn into a layer k times the frame in each direction (k x k ordered
//    grid), cleared to transparent, so each texel holds the model's colour
//    premultiplied by whether the model covers that sub-sample. The box
//    filter down to the frame gives every pixel its model colour times its
//    coverage (alpha = the covered fraction of its k^2 sub-samples), which
//    is blended over the video as premultiplied alpha:
//      out = layer + (1 - layer.a) video,
//    exactly what an MSAA resolve of the same samples over the video gives.
//    Unlike MSAA it shades every sub-sample: k^2 times the model's fragment
//    cost (docs/models.md#edges has the measured figures), which also
//    smooths speculars and textures that alias inside the model.
//
// Blending is in the sRGB-encoded bytes of the frame, as every other GLES2
// blend in the kiosk (no sRGB framebuffers); a hardware MSAA resolve on such a
// target averages the same bytes.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "gles/capabilities.hpp"
#include "gles/gl_objects.hpp"
#include "passes/framebuffer_state_guard.hpp"
#include "passes/camera_response.hpp"

namespace probelight::passes {

enum class EdgeStrategy {
  kOff,                         // one sample a pixel (edge_samples 1, or nothing fits)
  kMultisampleConfig,           // the bound framebuffer is multisampled: draw into it
  kMultisampleRenderToTexture,  // GL_EXT_multisampled_render_to_texture layer
  kOrderedGridSupersampling,    // core GLES2: k x k supersampled layer, box-filtered
};

// "off", "multisample_config", "multisample_render_to_texture",
// "ordered_grid_supersampling": the report's names.
const char* edgeStrategyName(EdgeStrategy strategy);

struct EdgeAntialiasing {
  EdgeStrategy strategy = EdgeStrategy::kOff;
  int samples = 1;            // per pixel: the MSAA count, or grid^2
  int grid = 1;               // k, the supersampled layer's factor (kOrderedGridSupersampling), else 1
  int requested_samples = 1;  // what was asked for
  std::string reason;         // one line: why this one

  bool usesLayer() const {
    return strategy == EdgeStrategy::kMultisampleRenderToTexture || strategy == EdgeStrategy::kOrderedGridSupersampling;
  }
  bool operator==(const EdgeAntialiasing&) const = default;
};

// The largest ordered grid the fallback uses: 4 x 4 = 16 sub-samples, where
// the coverage error is under 1/4 of the edge's step and each further step
// costs the model's whole fragment work again.
constexpr int kMaxSupersamplingGrid = 4;

// Pure: the strategy for a frame of width_px x height_px drawn into a
// framebuffer with target_samples (GL_SAMPLES of the bound framebuffer: 0 or
// 1 single-sampled), when requested_samples (ModelRendererSettings::
// edge_samples) are asked for; 1 or less: off.
//  - target_samples >= 2: kMultisampleConfig, with those samples.
//  - the EXT with GL_MAX_SAMPLES_EXT >= 2: kMultisampleRenderToTexture with
//    min(requested, max) samples.
//  - otherwise kOrderedGridSupersampling with the grid k = ceil(sqrt(requested))
//    in [2, kMaxSupersamplingGrid] (4 samples: 2 x 2; 5 to 16: 4 x 4; the
//    resolve reads 2 x 2 blocks with one bilinear fetch each, so k is even),
//    halved until k times the frame fits the GPU's texture, renderbuffer and
//    viewport limits; off when not even 2 x 2 fits.
EdgeAntialiasing chooseEdgeAntialiasing(const gles::Capabilities& capabilities, int requested_samples,
                                        int target_samples, int width_px, int height_px);

// Pixels of the frame, top row first (image row 0 at the top, as
// RenderTarget's convention): columns [x, x + width), rows [y, y + height).
struct PixelRect {
  int x = 0, y = 0, width = 0, height = 0;
  bool empty() const { return width <= 0 || height <= 0; }
  bool operator==(const PixelRect&) const = default;
};

// Pure: the frame's pixels a model within the box [min_w, max_w] (W) can
// touch, drawn as the model shader projects (pinhole, then the 5-term
// distortion per vertex, straight edges between), with margin_px more on
// every side, clipped to the frame; empty when it is all off the frame.
// The whole frame where this cannot be told cheaply: a corner nearer than
// near_m (or behind), or the box reaching so far out of the view that the
// distortion polynomial may fold (past 1.5 times the image corners' radius).
// Within that, the box's pinhole image is inside the rectangle of its
// corners' images, and the distortion, monotone along rows and columns
// there, takes that rectangle to a region bounded by its distorted outline
// (sampled 32 times a side; the margin covers the bow between samples).
// The layer's clear, the model's draw and the composite are cut to this.
PixelRect projectedBounds(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const glm::dvec3& min_w,
                          const glm::dvec3& max_w, double near_m, int margin_px);

// The layer of the two layer strategies and the pass that composites it
// over the frame. GPU objects: create and use with the context current.
class EdgeLayer {
 public:
  // Allocates the layer for `choice` (usesLayer()) at width_px x height_px
  // (times choice.grid), and the composite program. False with the reason in
  // `error` when the GPU refuses (an incomplete multisampled framebuffer, out
  // of memory); the caller may then try the next strategy.
  bool init(const gles::Capabilities& capabilities, const EdgeAntialiasing& choice, int width_px, int height_px,
            std::string& error);
  bool ready(const EdgeAntialiasing& choice, int width_px, int height_px) const {
    return layer_.valid() && choice == choice_ && width_px == width_px_ && height_px == height_px_;
  }

  // Binds the layer, sets the viewport to all of it and clears `region`
  // (projectedBounds) of it to transparent black (colour and depth), with
  // the scissor test cutting what is drawn to it. The caller's framebuffer,
  // viewport, clear colour and scissor are saved, for composite() to restore.
  void begin(const PixelRect& region);
  // Restores the caller's state and blends the resolved layer over the
  // region of its framebuffer (whose viewport covers the frame):
  // out = layer + (1 - layer.a) dst. Leaves blending and the depth test off.
  // With `noise`, a supersampled layer (addsNoiseAfterResolve) gets it here
  // (model_edges_composite.frag says why); `texture` holds its samples.
  bool composite(std::string& error, const SensorNoiseMatch* noise = nullptr,
                 const SensorNoiseTexture* texture = nullptr);
  // Whether the frame's noise goes in at the resolve (the ordered grids,
  // whose box filter would average it down) rather than in the model's shader.
  bool addsNoiseAfterResolve() const { return choice_.grid >= 2; }
  // Restores what begin() saved without compositing (a draw that failed).
  void restore();

  // GPU memory the layer holds (colour + depth, all samples).
  std::uint64_t bytes() const { return bytes_; }
  // The samples a pixel gets: grid^2, or what the EXT allocated (it may
  // round the count asked for up to one the GPU has).
  int samples() const { return samples_; }

 private:
  EdgeAntialiasing choice_;
  int width_px_ = 0, height_px_ = 0;
  gles::Texture layer_;
  gles::Renderbuffer depth_;
  gles::Framebuffer framebuffer_;
  std::optional<gles::Program> program_;
  std::optional<gles::Program> noise_program_;  // program_ with MATCH_SENSOR_NOISE, made on first use
  gles::FullScreenQuad quad_;
  std::uint64_t bytes_ = 0;
  int samples_ = 1;
  DrawTargetState saved_;  // the caller's, while the layer is bound
  PixelRect region_;
};

}  // namespace probelight::passes
