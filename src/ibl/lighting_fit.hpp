// The lighting fit, one sequence for every command: from the ball's 8-bit
// reflection map (and, where a bracket was merged, its HDR map) and the fit
// frame's pixels to the lights the object is shaded and shadowed with.
//
//   white border -> post -> clipped lights -> dome -> dominant light
//
// 1. The tag's white border (white_reference.hpp) is read in the fit frame
//    and what the ball's clipped highlights hide is given back to them, on a
//    copy of the 8-bit map.
// 2. The ball's post (post_reference.hpp), where the rig has one, divides
//    that light between the clipped regions.
// 3. The map the dome is fitted from: the bracket's HDR map when there is
//    one (nothing in it is clipped), else the corrected map when the border
//    could be used, else the 8-bit map. The clipped lights are what it holds
//    beyond the 8-bit map where that clipped: the frame-rate maps stay
//    8-bit, and these carry the rest.
// 4. The dome of lights (light_dome.hpp) and the dominant light, from it.
//
// The border and the post are read whenever the fit frame's ball is known,
// even when a bracket makes them unnecessary, so that a report can show
// what they say. No GL: `run`, `analyze` and `render` all call this, as
// Filament's libs/ibl keeps its sequences out of its tools.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/light_dome.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/post_reference.hpp"
#include "ibl/surface_shading.hpp"
#include "ibl/white_reference.hpp"

namespace probelight::ibl {

struct LightingFitSettings {
  CameraTransfer camera_transfer;  // how the camera's codes decode to linear light
  bool white_reference = true;     // lights.white_reference (analyze: unless --no-white-ref)
  bool post_reference = true;      // lights.post_reference (analyze: unless --no-post-ref)
  LightDomeSettings dome;          // lights.dome
  int max_clipped_lights = SceneLighting::kMaxClippedLights;
};

struct LightingFitInputs {
  const CubeMapRGB* map_8bit = nullptr;   // the ball's reflection map as the camera's 8 bits gave it
  const std::vector<float>* validity = nullptr;  // of map_8bit (1 where the ball shows the direction)
  const CubeMapRGB* hdr_map = nullptr;    // a merged bracket of the same view, or null
  // The fit frame's ball (null: its tag was not found) and pixels: the
  // border, the post and which ball pixels clipped are read from them.
  const MirrorBallView* view = nullptr;
  RgbPixelReader read_pixel;
  std::optional<WhiteRing> white_ring;  // the tag's white border; none: not read
  RigGeometry rig;                      // tag_white_albedo, the post, probe_reflectance
};

enum class LightingFitMethod {
  kEightBit,             // the 8-bit map as it is (what it clipped is lost)
  kBracket,              // a merged bracket
  kWhiteBorder,          // the 8-bit map, its clipped texels given the border's light
  kWhiteBorderAndPost,   // ... divided between the clipped regions by the post
};
const char* toString(LightingFitMethod method);

struct LightingFit {
  LightingFitMethod method = LightingFitMethod::kEightBit;
  // The map the dome was fitted from when it is not the 8-bit one (a
  // bracket's, or the 8-bit map corrected by the border).
  std::optional<CubeMapRGB> fitted_map;
  // What the border and the post said (nullopt: not read: no ball, or no ring).
  std::optional<WhiteBorderReading> border;
  std::optional<WhiteReferenceResult> border_correction;
  std::optional<PostCorrection> post;
  double border_ms = 0.0;  // reading and correcting with the border and the post
  std::vector<ClippedLight> clipped_lights;
  std::vector<DomeLight> dome;
  DominantLight dominant;
  // What a user should hear about (one line each, no prefix): a border that
  // could not restore the clipped light, a post that disagrees. Only for the
  // method that had to rely on them (none with a bracket).
  std::vector<std::string> warnings;
};

LightingFit fitLighting(const LightingFitInputs& inputs, const LightingFitSettings& settings);

// The clipped lights as SceneLighting shades them (E / pi added to the
// diffuse map's value), each at `scale` of what was measured (empty: 1).
void setClippedLights(SceneLighting& lighting, const std::vector<ClippedLight>& lights,
                      const std::vector<double>& scale = {});

}  // namespace probelight::ibl
