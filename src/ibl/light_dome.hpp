// A dome of directional lights fitted to the environment's upper hemisphere,
// for shadows (seeds B and C), and the dominant light.
//
// Each light stands for a region R of the upper hemisphere. It is placed and
// coloured from the region's first moment, per channel c,
//   M_c = integral over R of L_c(w) w dw    (a vector),
// with the direction d = M_Y / |M_Y| (Y: luminance) and rgb_c = M_c . d.
// For any normal n that sees the whole region (n . w >= 0 on R),
//   integral over R of L_c max(0, n . w) dw = n . M_c,
// which the light gives back exactly as rgb_c max(0, n . d) whenever M_c is
// parallel to M_Y (a region of one colour). So the dome reproduces the
// upper-hemisphere irradiance by construction wherever a region does not
// straddle the normal's horizon, instead of approximately (seed B's "average
// colour behind the light", seed C's energy centroid with total energy).
//
// Placements:
// - kFixedRegions (seed B): the same regions whatever the room: a zenith cap
//   and a ring of azimuth sectors, all of equal solid angle.
// - kMedianCut (seed C, Debevec 2005): the hemisphere is cut recursively at
//   the energy median of each region, along its longer side (azimuth
//   measured times cos(elevation), so that sides compare as arcs). Regions
//   end with equal energy, so a lamp holding a quarter of the light is cut
//   into several regions that each mix a piece of it with sky.
// - kClustered: energy-weighted k-means on the sphere (Lloyd's iterations:
//   each cell to the nearest light, each light to its cells' first moment),
//   which minimises the energy-weighted angular spread of the lights, i.e.
//   the blur of their shadows. The lamp's pieces merge back into one light at
//   its centre; regions are the lights' Voronoi cells. k-means ends in a
//   local optimum that depends on its start: it is run from the median cut
//   and from the fixed regions, and the dome that reproduces the upper
//   hemisphere's irradiance better (at the worst normal with z >= 0.5) is kept.
//
// Each light also carries its region's angular spread (within what angle of
// its direction half its energy lies), which sets how soft its shadow is.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "ibl/cube_map.hpp"

namespace probelight::ibl {

enum class DomePlacement { kFixedRegions, kMedianCut, kClustered };
const char* toString(DomePlacement placement);  // "fixed", "median_cut", "clustered"

struct LightDomeSettings {
  int light_count = 8;
  DomePlacement placement = DomePlacement::kClustered;
  // The upper hemisphere is resampled into this many cells (azimuth x
  // elevation), 2x2 bilinear cube samples each: 256 x 64 is 1.4 degrees, the
  // texel pitch of a 64^2 face at its centre.
  int azimuth_cells = 256;
  int elevation_cells = 64;
};

struct DomeLight {
  glm::dvec3 direction_w{0.0, 0.0, 1.0};  // unit, toward the light, z >= 0
  glm::dvec3 rgb{0.0};                    // irradiance at normal incidence, the cube's units
  // The angle from `direction_w` within which half the region's energy
  // lies: a lamp's radius when a lamp dominates its region (how soft its
  // shadow is), wider for spread sky.
  double spread_rad = 0.0;
  double solid_angle_sr = 0.0;  // of its region
};

// `radiance`: linear radiance cube (the reflection map). `validity`: per
// texel in [0, 1] (face-major as EnvironmentMaps::read* gives it), or null
// for all valid; directions the ball could not see (validity < 0.5) take the
// mean radiance of the valid upper hemisphere, a neutral guess that keeps the
// dome's total energy. Never throws; non-finite texels count as 0. Returns
// light_count lights (fewer only when light_count < 1: none).
std::vector<DomeLight> fitLightDome(const CubeMapRGB& radiance, const std::vector<float>* validity,
                                    const LightDomeSettings& settings = {});

// Irradiance the dome gives a surface of normal n: sum of rgb max(0, n . d).
glm::dvec3 domeIrradiance(const std::vector<DomeLight>& lights, const glm::dvec3& normal);

// The dominant light: direction and colour.
//
// An 8-bit camera clips the sun together with the bright sky around it, so
// the brightest ball pixel only says "somewhere in the clipped blob" (misses
// of 20 degrees and more on real skies). Where the map has clipped texels
// (any channel at or above 0.98 clip_level), the direction is the centroid
// (solid-angle weighted) of the largest clipped blob in the upper
// hemisphere: with every clipped texel equally bright as far as the frame
// can tell, the largest blob holds the most light, and its centre is the
// best guess the frame allows. Measured against the true sun
// (tests/accuracy): 1.7 degrees in the simulated sun_sky, 13 degrees in the
// real Kerner sky, whose clipped blob is 0.5 sr and lopsided. Weighting the
// centroid toward the blob's deepest cells moved it by under a degree
// either way, so it is not done. Without clipping (an HDR map from an
// exposure bracket, or a dim room), the source is the 4-connected region at
// least half as bright as the brightest cell that carries the most power,
// and its direction the luminance-weighted centre: a sun is a few cells, a
// soft box its whole face, whose brightest cell could sit anywhere on it.
// The colour is the rgb of the dome light nearest the direction.
struct DominantLight {
  bool found = false;
  glm::dvec3 direction_w{0.0, 0.0, 1.0};
  glm::dvec3 rgb{0.0};
  bool from_clipped_region = false;
  double clipped_solid_angle_sr = 0.0;
};
// `clip_level`: the cube value a clipped camera pixel decodes to (1 /
// probe_reflectance for the sRGB reflection map); <= 0: no clipping test.
DominantLight findDominantLight(const CubeMapRGB& radiance, const std::vector<float>* validity,
                                const std::vector<DomeLight>& lights, double clip_level,
                                const LightDomeSettings& settings = {});

}  // namespace probelight::ibl
