// probelight.yaml: the pipeline's settings. Every field is optional; a file
// only lists what it changes. board/probelight.yaml documents them all.
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "display/kms_display.hpp"
#include "input/gpio_button.hpp"
#include "input/status_led.hpp"
#include "stages/pipeline_settings.hpp"

namespace probelight {

struct SimConfig {
  std::string env = "studio";
  std::string camera_path = "orbit";
  double noise_sigma = 1.5;  // 8-bit code values
  double lens_blur_sigma = 0.0;  // px: the simulated lens's Gaussian blur (sim::SceneConfig::lens_blur_sigma_px)
  int seed = 1;
  // Lighting that changes during the run (for testing map refresh and
  // recalibration): the environment turning, and a lamp switching.
  double sun_azimuth_rate_deg_per_frame = 0.0;
  // The whole environment turned about +Z (counter-clockwise from above):
  // to put its brightest light where a view's ball cannot see it.
  double environment_rotation_deg = 0.0;
  int lamp_on_frame = -1;   // -1: never
  int lamp_off_frame = -1;  // -1: stays on
  // Where the simulated ball really sits relative to rig.yaml's probe_center
  // (metres, W): a rig measured wrong, for testing probe_refinement.
  glm::dvec3 ball_offset_m{0.0};
  // "rgb", or a camera's format: "yuv420", "nv12" (a Pi's camera), "yuyv"
  // (a USB webcam), "rgb888", "bgr888", "xrgb8888" (vimc and other
  // RGB sensors' pipelines). Frames then come as such a camera gives them
  // (YUV full-range Rec601), so the detection's luma and the GPU's
  // conversion of that format run as on the board. MJPEG is not simulated.
  std::string pixel_format = "rgb";
  // The camera disappearing mid-run (for testing the reconnect): frame N
  // fails, then the first `camera_lost_restarts` reconnects fail too.
  int camera_lost_at_frame = -1;  // -1: never
  int camera_silent_at_frame = -1;  // -1: never
  double camera_silent_s = 5.0;
  int camera_lost_restarts = 2;
  // The shortest exposure the simulated sensor can take (microseconds; 0: any),
  // as real sensors have one: a bracket asking for less gets this.
  double min_exposure_us = 0.0;
  // Whether the simulated camera says that shortest exposure (a camera's
  // ExposureTime control has a minimum; a source may not tell it), so that
  // a bracket plans its ladder to it rather than finding it.
  bool min_exposure_reported = true;
  // false: the simulated camera has no exposure control (as vimc's sensor
  // has none): brackets are refused and the lights fitted from one frame.
  bool exposure_control = true;
  // The simulated sensor's own exposure, in stops from the scene's (its
  // auto exposure): every frame not in a bracket is taken at 10 ms x
  // 2^exposure_stops. scripts/replay-frames.sh renders a bracket's
  // exposures this way for a replay to serve (ImageFrameSource's exposure sets).
  double exposure_stops = 0.0;
  // Auto exposure and white balance moving mid-run (SimCameraOptions'
  // response_shift_*): from response_shift_from_frame to
  // response_shift_until_frame (-1: never / to the end).
  int response_shift_from_frame = -1;
  int response_shift_until_frame = -1;
  double exposure_shift_stops = 0.0;
  double white_balance_shift_red = 1.0;
  double white_balance_shift_blue = 1.0;
  // The simulated shutter stays open for each frame's exposure time while
  // the camera moves: motion blur (SimCameraOptions::motion_blur).
  bool motion_blur = false;
  // The simulated camera has a lens it can focus (as the Camera Module 3):
  // camera.yaml's lens_position_dioptres is set, and every frame's metadata
  // says where the lens is (SimCameraOptions::lens_control). false: a
  // fixed-focus camera, as vimc.
  bool lens_control = false;
  // Buffers in the simulated camera's pool: an exposure change reaches the
  // frames from this many after the newest one handed out (its latency, as
  // a real pipeline's queued requests give one).
  int camera_buffers = 3;
};

struct ButtonConfig {
  GpioButtonSettings gpio;  // chip, line, debounce and long press (--button gpio)
  StatusLedSettings led;    // on the button's chip; line -1: none
};

// The board's screen (--display kms).
struct DisplayConfig {
  KmsDisplaySettings kms;
};

// Faults injected on purpose, for long runs that must show they cost
// nothing (scripts/soak.sh); off by default.
struct FaultConfig {
  // Any source, replayed frames included (which then reconnect as a camera
  // does): the camera is lost after every this many frames (0: never)...
  int camera_loss_every_frames = 0;
  // ... and this many reconnects fail before it is back.
  int camera_loss_failed_restarts = 1;
};

// The stages' sections (stages/pipeline_settings.hpp), and the kiosk's own.
struct AppSettings : PipelineSettings {
  ButtonConfig button;
  DisplayConfig display;
  SimConfig sim;
  FaultConfig faults;
  int save_every = 1;     // write every K-th composited frame; 0 = none
  // OUT/resources.csv: RSS, open descriptors and live GL objects after the
  // first frame and every this many (app/resource_log.hpp); 0: none.
  int resources_every_frames = 0;
};

// Reads probelight.yaml. Throws config::ConfigError (one line, file + field).
AppSettings loadAppSettings(const std::string& path);

}  // namespace probelight
