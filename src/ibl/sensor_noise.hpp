// The frame's sensor noise, measured where the frame is flat by
// construction: inside the printed tag's cells. Each cell is one ink, so
// away from its edges (pose error, lens blur, a pixel's own footprint) what
// varies from pixel to pixel is the light's slow gradient and the noise. A
// plane fitted to each cell's interior takes the gradient; the residual is
// the noise. The cells fall into two levels (black and white ink), so the
// noise is known at two signal levels: what a composite needs to give a
// virtual object the grain the video around it has (Klein & Murray,
// "Compositing for small cameras", 2008).
//
// Which cells are black is not looked up: a cell's level is its measured
// mean, split at the middle between the darkest and brightest cells. A
// cell the tag does not fill (a circle family's corner), or one crossed by
// a shadow's edge, has a residual far above its level's and is left out.
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "ibl/white_reference.hpp"

namespace probelight::ibl {

// The square grid of the printed tag's cells around its centre (W: tag
// centred on the origin in z = 0, edges along X and Y): grid_cells x
// grid_cells cells of cell_m, the family's total_width (tag36h11: its
// 8-cell black border and the white ring around it, 10 cells), each
// tag_size / width_at_border.
struct TagCellGrid {
  int grid_cells = 0;
  double cell_m = 0.0;
};
TagCellGrid tagCellGrid(int width_at_border_cells, int total_width_cells, double tag_size_m);

struct SensorNoiseSettings {
  // Pixels whose centre is nearer a cell's edge than this are left out:
  // half a pixel's diagonal (0.71 px) plus a lens blur's reach.
  double edge_clearance_px = 2.0;
  // A cell needs this many interior pixels (the plane takes 3 degrees of
  // freedom of them).
  int min_pixels_per_cell = 9;
  // Each level needs this many cells.
  int min_cells_per_level = 3;
  // A cell with a channel at or above clip_code, or at or below floor_code,
  // has its noise cut off by the 8-bit range: left out.
  int clip_code = 250;
  int floor_code = 4;
  // A cell whose residual variance exceeds this many times its level's
  // median is not flat (an edge, a shadow's border, floor): left out.
  double outlier_variance_ratio = 4.0;
};

// The noise at one signal level, per channel, in 8-bit code values, as the
// frame shows it (its own 8-bit rounding included: 1/12 code^2 of it).
struct NoiseAtLevel {
  glm::dvec3 mean_code{0.0};
  glm::dvec3 sigma_code{0.0};
  long pixels = 0;
  int cells = 0;
};

enum class SensorNoiseStatus { kMeasured, kNotInView, kTooSmall, kNotFlat };
const char* toString(SensorNoiseStatus status);

struct SensorNoiseReading {
  SensorNoiseStatus status = SensorNoiseStatus::kNotInView;
  std::string message;
  NoiseAtLevel dark;
  NoiseAtLevel bright;
  int cells_in_view = 0;
  int cells_left_out = 0;  // clipped, too few pixels, or not flat
};

SensorNoiseReading measureSensorNoise(const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                                      const TagCellGrid& grid, const RgbPixelReader& read_pixel,
                                      const SensorNoiseSettings& settings);

// The noise a composite adds to an object pixel of 8-bit value `code`, per
// channel, in code values: the frame's at that level (linear between the
// two levels measured, constant beyond them), less the 1/12 code^2 of the
// frame's own rounding, which the composite's rounding to 8 bits adds back.
// The shader (camera_response.glsl) evaluates the same.
struct AddedNoiseModel {
  glm::dvec3 dark_code{0.0};
  glm::dvec3 bright_code{255.0};
  glm::dvec3 dark_sigma_code{0.0};
  glm::dvec3 bright_sigma_code{0.0};
};
AddedNoiseModel addedNoiseModel(const NoiseAtLevel& dark, const NoiseAtLevel& bright);
glm::dvec3 addedNoiseSigmaCode(const AddedNoiseModel& model, const glm::dvec3& code);

}  // namespace probelight::ibl
