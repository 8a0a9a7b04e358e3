// `probelight analyze`: one camera frame in, what the system sees out.
// Runs the same stages as `probelight run` (src/stages: track, maps, the
// lighting fit of ibl/lighting_fit.hpp, and for render shadows and compose),
// with the same probelight.yaml, on one frame and its bracket, and writes
// DIR/analysis.json and
// pictures a person can check by eye: overlay.png (tag outline, W axes, ball
// outline on the frame), ball.png (the ball, enlarged), reflection_cross.png
// and diffuse_cross.png (the cube maps unfolded).
//
// Exit status: 0 ok; 1 runtime failure (GPU); 2 bad flag, file or frame;
// 3 the tag or the ball was not found (analysis.json still holds what was
// found, and "error" says why).
#pragma once

#include <array>
#include <iosfwd>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <opencv2/core.hpp>

#include "app/command_line.hpp"
#include "app/exit_status.hpp"
#include "core/status.hpp"
#include "ibl/cube_map.hpp"

namespace probelight {


// The normals of analysis.json's "irradiance", unit, in W, in this order:
// +X, -X, +Y, -Y, +Z, -Z, then the 8 diagonals (sx, sy, sz)/sqrt(3) with
// sx, sy, sz in {+1, -1}, x varying slowest and + before -.
std::array<glm::dvec3, 14> analysisNormals();

// The unfolded cube as a horizontal cross, 4 tiles wide and 3 high, seen from
// inside the cube. Middle row, left to right: -X, +Y, +X, -Y (turning right
// as one reads, like a panorama); +Z (up) above the +Y tile and -Z (down)
// below it, each joined to +Y along their shared edge.
enum class CrossTile { kPosX, kNegX, kPosY, kNegY, kPosZ, kNegZ };
// Column and row (in tiles) of a face's tile.
cv::Point crossTileCell(CrossTile tile);
// World direction (unit) shown at (a, c) of a tile: a in [-1, 1] from the
// tile's left edge to its right, c in [-1, 1] from its top edge to its bottom.
glm::dvec3 crossTileDirection(CrossTile tile, double a, double c);

struct CrossPictureOptions {
  std::string title;          // written in the empty top-left cell
  double display_scale = 1.0;  // pixel = sRGB(min(1, linear * display_scale))
  int tile_px = 128;          // a multiple of the map's face size keeps texels square blocks
  // Per texel, as EnvironmentMaps::read* returns it (face-major); texels
  // below 0.5 (not seen by the ball) are hatched. Empty: none hatched.
  std::vector<float> validity;
};

// The cross picture (8-bit BGR, 4 x 3 tiles, labelled), each pixel the map's
// nearest texel in that direction, so every texel is a visible block.
cv::Mat renderCubeCross(const ibl::CubeMapRGB& map, const CrossPictureOptions& options);

// The display scale that shows the brightest unclipped texel as white:
// 1 / (largest channel of the brightest texel whose channels all stay below
// 0.99 * clip_level), over texels with validity >= 0.5 (all when validity is
// empty). 1 / clip_level when every texel is clipped or the map is black.
double crossDisplayScale(const ibl::CubeMapRGB& map, const std::vector<float>& validity, double clip_level);

// A failure comes back as a Status (kNotFound: the tag or the ball was not
// found; analysis.json still says what was); main() turns it into the exit
// status.
Status runAnalyze(const AnalyzeOptions& options, std::ostream& log);

// `probelight render`: analyze, then the object composited into the frame
// with its shadow on the ground (DIR/composite.png, the frame's size); the
// same exit statuses.
Status runRender(const RenderOptions& options, std::ostream& log);

}  // namespace probelight
