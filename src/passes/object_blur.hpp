// The frame's blur given to the virtual object (issue 19). The frame as
// drawn before the object (the video and the shadow) is copied, under the
// object's region, into a base texture; the object is drawn into a layer
// of the frame's size, premultiplied by its
// coverage over transparent black; then the layer passes through a
// separable Gaussian in linear light and is mixed over the base in linear
// light by its blurred coverage: out = G * L + (1 - G * a) base, encoded
// with the camera's transfer (object_blur.frag). The object's silhouette and
// texture soften as the lens softened the light around it; the base,
// blurred by the lens already, is taken as locally even under the object's
// soft edge (exact where it is). Mixing in the encoded bytes instead, as
// GL's blending would, narrows a bright object's edge over a dark floor by
// a third at a half-pixel blur.
//
// The sigma to add is the frame's edge spread (ibl/edge_blur) less what the
// object's own edges have: a pixel's area, 1/12 px^2, for anti-aliased
// edges (objectBlurSigmaPx). With noise matched, the noise goes in after the
// blur, at the composite, and not in the object's shader.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "gles/gl_objects.hpp"
#include "passes/framebuffer_state_guard.hpp"
#include "ibl/color_transfer.hpp"
#include "passes/camera_response.hpp"
#include "passes/edge_antialiasing.hpp"

namespace probelight::passes {

// Taps either side the shaders are built for, at most: 3 sigma of a 4 px blur.
constexpr int kMaxObjectBlurTaps = 12;
// Taps either side of a motion smear's box, at most: 2 x 16 + 1 samples
// keep their spacing under a pixel up to a 33 px smear.
constexpr int kMaxMotionSmearTaps = 16;

// Pure: the box of a motion smear `smear_px` long (its whole length,
// centred) as 2 taps + 1 equal samples `step_px` apart, at the middles of
// as many equal parts of it (the midpoint rule). taps = ceil(length / 2)
// within 1..kMaxMotionSmearTaps, so the spacing is under a pixel up to
// that length: with the layer's bilinear taps, the sum is then the box's
// integral up to the interpolation between neighbouring texels.
struct MotionSmearTaps {
  int taps = 0;          // either side of the centre
  glm::dvec2 step_px{0.0};
};
MotionSmearTaps motionSmearTaps(const glm::dvec2& smear_px);

// Pure: sigma_px^2 = frame_edge_sigma_px^2 - object_edge_variance_px2, 0 when
// the object's edges are already as soft.
double objectBlurSigmaPx(double frame_edge_sigma_px, double object_edge_variance_px2 = 1.0 / 12.0);

// Pure: the Gaussian's weights for offsets 0..taps (the centre first; each
// side's once), taps = ceil(3 sigma) within 1..kMaxObjectBlurTaps, summing
// to 1 over -taps..taps.
std::vector<float> objectBlurWeights(double sigma_px);

class ObjectBlurLayer {
 public:
  // The base, the layer and the horizontal pass's target, width_px x
  // height_px RGBA8, with a 16-bit depth buffer for the object's own draw.
  bool init(int width_px, int height_px, const ibl::CameraTransfer& camera_transfer, std::string& error);
  bool ready(int width_px, int height_px) const {
    return layer_.valid() && width_px == width_px_ && height_px == height_px_;
  }
  // Copies the caller's framebuffer (whose viewport covers the frame one
  // to one), the frame drawn so far, under `region` grown by the blur's
  // reach, as the base; then binds the layer for the object's draw,
  // cleared to transparent black there (the rest is not read). Saves the
  // caller's framebuffer, viewport, clear colour and scissor.
  // `smear_px`: the camera's motion over the exposure (zero: none), a box
  // along it applied before the lens's Gaussian (motion blur; the lens
  // spreads each instant's light, the sensor sums the instants: the two
  // commute).
  void beginObject(const PixelRect& region, double sigma_px, const glm::dvec2& smear_px = glm::dvec2(0.0));
  // Over the region of the caller's framebuffer, the blurred object mixed
  // into the base, with `noise` added after the blur when given. Restores
  // what beginObject() saved; blending and depth test left off.
  bool composite(const SensorNoiseMatch* noise, const SensorNoiseTexture* noise_texture, std::string& error);
  // Restores what beginObject() saved without compositing (a draw that failed).
  void restore();

 private:
  // kHorizontal: a pass into a layer (the smear's box, or the Gaussian
  // along rows); kComposite: the last, into the caller's framebuffer.
  enum class Pass { kHorizontal, kComposite };
  // One pass into a layer: `from` read along `step_px` with `weights`.
  bool passIntoLayer(const gles::Texture& from, const gles::Framebuffer& to, const glm::dvec2& step_px,
                     const std::vector<float>& weights, std::string& error);
  const gles::Program* program(Pass pass, int taps, bool noise, std::string& error);
  void scissorTo(const PixelRect& rect, int viewport_x, int viewport_y) const;

  int width_px_ = 0, height_px_ = 0;
  ibl::CameraTransfer camera_transfer_;
  gles::Texture base_, layer_, horizontal_;
  gles::Renderbuffer depth_;
  gles::Framebuffer layer_framebuffer_, horizontal_framebuffer_;
  gles::FullScreenQuad quad_;
  std::map<std::tuple<Pass, int, bool>, gles::Program> programs_;
  // The object's region grown by the reach (the composite's and the
  // base's), by three reaches (the layer passes') and by four (the
  // layer's clear); each within the frame.
  PixelRect region_, passes_region_, cleared_region_;
  std::vector<float> weights_;
  MotionSmearTaps smear_;
  DrawTargetState saved_;  // the caller's, while the layer is bound
};

}  // namespace probelight::passes
