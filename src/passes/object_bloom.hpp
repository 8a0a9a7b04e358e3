// The lens's glare around the virtual object's light above white (issue 19,
// seed C's bloom). A camera's pixel holds at most white; the light a lens
// spreads around a bright source (veiling glare, the bloom round a lamp)
// lands on the pixels beside it. The frame's own lamps already show it;
// the object's highlights above white (a specular peak, a mirror finish
// showing a clipped lamp, an emissive part) get it here, so they look as
// bright as the room's:
//   1. the bright pass: the object drawn again into a layer at 1/downsample
//      of the frame's resolution, writing its light beyond white,
//      e = max(light - 1, 0) (camera_response.glsl's BLOOM_BRIGHT_PASS);
//   2. a separable Gaussian of the lens's glare spread over it, in linear
//      light (object_bloom.frag);
//   3. the spread light added to the frame drawn so far, in linear light,
//      over the object's region grown by the spread, and encoded with the
//      camera's transfer.
// The light beyond white is spread, not invented: the halo's light summed
// over the frame is the light the clip would have thrown away, less what
// lands on pixels already white (tests/gles/object_bloom_test.cpp).
#pragma once

#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "gles/gl_objects.hpp"
#include "ibl/color_transfer.hpp"
#include "passes/camera_response.hpp"
#include "passes/edge_antialiasing.hpp"
#include "passes/framebuffer_state_guard.hpp"

namespace probelight::passes {

// The layer's resolution divisor for a glare spread: the blur's taps (at
// most kMaxObjectBlurTaps, 3 sigma) reach it at the layer's resolution.
int bloomDownsampleFor(double sigma_px);

class ObjectBloom {
 public:
  // For a frame of width_px x height_px and a glare spread of sigma_px
  // (frame pixels).
  bool init(int width_px, int height_px, double sigma_px, const ibl::CameraTransfer& camera_transfer,
            std::string& error);
  bool ready(int width_px, int height_px, double sigma_px) const {
    return layer_.valid() && width_px == width_px_ && height_px == height_px_ && sigma_px == sigma_px_;
  }
  // `object_region` (frame pixels): where the object may be. Saves the
  // caller's framebuffer, viewport, clear colour and scissor, and binds the
  // bright layer over the region grown by the spread, cleared: the caller
  // then draws the object with its bright pass on.
  void beginBrightPass(const PixelRect& object_region);
  // The spread light added over the grown region of the caller's
  // framebuffer (whose viewport covers the frame one to one). Restores
  // what beginBrightPass() saved; blending and depth test left off.
  bool composite(std::string& error);
  // Restores what beginBrightPass() saved, adding nothing (a draw failed).
  void restore() { saved_.restore(); }

  int downsample() const { return downsample_; }
  const PixelRect& region() const { return region_; }

 private:
  enum class Pass { kHorizontal, kComposite };
  const gles::Program* program(Pass pass, std::string& error);

  int width_px_ = 0, height_px_ = 0, downsample_ = 2;
  int layer_width_ = 0, layer_height_ = 0;
  double sigma_px_ = 0.0;
  std::vector<float> weights_;  // at the layer's resolution
  ibl::CameraTransfer camera_transfer_;
  gles::Texture base_, layer_, horizontal_;
  gles::Renderbuffer depth_;
  gles::Framebuffer layer_framebuffer_, horizontal_framebuffer_;
  gles::FullScreenQuad quad_;
  std::map<Pass, gles::Program> programs_;
  PixelRect region_;        // grown by the spread, within the frame (frame pixels)
  PixelRect layer_region_;  // the same in layer texels, covering it
  DrawTargetState saved_;
};

}  // namespace probelight::passes
