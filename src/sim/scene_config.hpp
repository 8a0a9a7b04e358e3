// Everything that describes a simulated scene: camera, rig, environment,
// lighting over time, camera path, and the sensor model. Plain data, so a test
// or the app can start from defaultScene() and change one field.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"

namespace probelight::sim {

// Bad scene input (unknown name, unreadable file, value out of range). The
// message is one line and names the field or file.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Lighting that changes with the frame index, for tests of map refresh.
struct LightingScript {
  // The whole environment (sun, sky, walls, or an HDR file) turns about +Z by
  // this much per frame, which moves the sun's azimuth.
  double sun_azimuth_rate_deg_per_frame = 0.0;
  // A bright soft box fixed in the room, on for frames [lamp_on_frame,
  // lamp_off_frame). -1 for lamp_on_frame: never; -1 for lamp_off_frame: stays on.
  std::int64_t lamp_on_frame = -1;
  std::int64_t lamp_off_frame = -1;
  double lamp_azimuth_deg = 200.0;   // from +X toward +Y
  double lamp_elevation_deg = 35.0;  // above the horizon
  double lamp_width_deg = 20.0;      // extent in azimuth
  double lamp_height_deg = 20.0;     // extent in elevation
  // Lamp radiance as a multiple of the environment's mean sky radiance E_up/pi,
  // so that it is "bright" whatever the environment's units.
  double lamp_relative_radiance = 40.0;
  glm::dvec3 lamp_colour{1.0, 0.93, 0.8};
};

// Camera motion, parameterised by frame index. Angles in degrees; the eye sits
// at look_at + distance * (cos(el) cos(az), cos(el) sin(az), sin(el)).
struct CameraPathConfig {
  std::string name = "orbit";  // one of cameraPathNames()
  // Unset: halfway between the tag centre and the ball centre.
  std::optional<glm::dvec3> look_at_w;
  double distance_m = 0.6;
  double elevation_deg = 40.0;
  double azimuth_start_deg = -90.0;  // -90: camera on the -Y side, tag upright, ball on the right
  // Negative so the default orbit sweeps ~230 deg (about 38 s at 30 fps)
  // before the ball starts to hide the tag (camera on the +X side).
  double azimuth_rate_deg_per_frame = -0.2;
  // slow_wobble: hand-held-like drift around the static pose.
  double wobble_angle_deg = 2.0;
  double wobble_distance_m = 0.02;
  // hand_held_sweep: an arc around the rig and back, with the wobble on top.
  double sweep_azimuth_deg = 35.0;    // either side of azimuth_start_deg
  double sweep_elevation_deg = 15.0;  // risen at the arc's middle
  double sweep_seconds = 3.0;         // one way
  // pan: the camera turning to and fro about its own vertical axis (the
  // image's columns) through its centre, as a hand pans a phone,
  // pan_amplitude_deg either side of the
  // static pose, a sine of period pan_period_s at 30 fps: the whole image
  // sweeps sideways, fastest (2 pi amplitude / period, 63 deg/s by default:
  // 7 px over a 10 ms exposure at f 600) through the middle.
  double pan_amplitude_deg = 10.0;
  double pan_period_s = 1.0;
  // random: one independent pose per frame, see RandomPoseRange.
  double random_min_distance_m = 0.45;
  double random_max_distance_m = 0.75;
};

// The simulator's render threads: 2 (a desktop's spare cores beside the
// kiosk's own), or the environment's PROBELIGHT_SIM_THREADS, a whole number
// from 1 to 64. The tests' runner sets it to the processors it gives each
// test (tests/tiers.cmake), so that two tests under `ctest -j2` do not put
// four render threads on two cores. Throws std::invalid_argument, naming
// the variable, for any other value.
int defaultRenderThreads();

struct SceneConfig {
  CameraIntrinsics camera;
  RigGeometry rig;

  // Environment: a name from environmentNames() or a lat-long .hdr/.exr file.
  std::string environment = "sun_sky";
  double environment_rotation_deg = 0.0;  // about +Z, counter-clockwise seen from above
  LightingScript lighting;

  CameraPathConfig camera_path;

  // Materials (albedo 0..1). The floor gets a mild smooth texture of +-contrast
  // around floor_albedo (its mean stays floor_albedo).
  double tag_black_albedo = 0.04;
  double tag_white_albedo = 0.85;
  double floor_albedo = 0.35;
  double floor_texture_contrast = 0.12;
  double post_albedo = 0.5;
  double post_radius_m = 0.003;

  // Sensor. Exposure: camera linear value = radiance * exposure, then clip at 1.
  // Auto: chosen once (frame 0 lighting) so that an upward-facing 0.85 white
  // patch reads 0.5 linear.
  bool auto_exposure = true;
  double fixed_exposure = 1.0;  // used when auto_exposure is false
  double noise_sigma_code = 1.5;  // Gaussian, in 8-bit code values, added after sRGB encoding
  // The lens's blur: a Gaussian point spread of this sigma in pixels over
  // the camera's linear light (before clipping, as optics spread light
  // before the sensor saturates), sampled at whole-pixel offsets
  // (lensBlurKernel); 0: none. On top of each pixel's own area.
  double lens_blur_sigma_px = 0.0;
  // n x n regular sub-pixel samples per pixel; 0 (needs edge samples): a
  // pixel that no edge crosses is the mean of its four corners' radiance,
  // about one ray a pixel (World's traceFrame says why that is as accurate).
  int supersample_per_axis = 0;
  // Pixels that an edge crosses (object silhouettes, tag cells), and every
  // pixel showing the mirror ball (where a sun's reflection is smaller than
  // a regular sub-sample), are integrated over their area with this many
  // jittered samples per axis, as a sensor does; 0 turns it off (regular
  // samples only).
  int edge_samples_per_axis = 8;
  std::uint64_t seed = 1;         // noise and random camera poses
  // Threads that render a frame: 2, or PROBELIGHT_SIM_THREADS where set
  // (defaultRenderThreads). The frame is the same for any count.
  int render_threads = defaultRenderThreads();
};

// The default: 640x480, f=600 px, mild barrel distortion; tag36h11 id 0 of
// 0.10 m; a 0.03 m ball at (0.12, 0, 0.08) on a post; sun_sky; a slow orbit at
// 0.6 m and 40 deg elevation (ball radius ~30 px).
SceneConfig defaultScene();

// The lens blur's 1-D weights for offsets -radius..radius (radius
// ceil(4 sigma)): the Gaussian sampled at whole pixels, normalised to a
// sum of 1; applied along rows, then columns. Its variance,
// sum k^2 w_k, is the blur the frame holds besides the pixel's area (a
// sampled Gaussian of sigma 0.5 has 0.215, not 0.25).
std::vector<double> lensBlurKernel(double sigma_px);
double lensBlurKernelVariance(const std::vector<double>& kernel);

// Names accepted for SceneConfig::environment (besides file paths) and for
// CameraPathConfig::name, for the app's --env / --path choices.
const std::vector<std::string>& environmentNames();
const std::vector<std::string>& cameraPathNames();

}  // namespace probelight::sim
