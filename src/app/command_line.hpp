// Command-line parsing for `probelight <command> [flags]` (with CLI11). A bad
// flag is a UsageError: one line naming the flag, and exit status 2. -h or
// --help after a command is HelpRequested: its flags, printed, exit status 0.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <glm/glm.hpp>
#include <vector>

namespace probelight {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// `text` with its control characters written as C escapes (\n, \t, \x1b),
// for a message that echoes an argument: it stays one printable line.
std::string printable(const std::string& text);

// Thrown by the parse functions for -h or --help: `text` is the command's
// help (what it does, each flag on one line, its exit statuses). Not an
// std::exception, so no catch-all reports it as an error.
struct HelpRequested {
  std::string text;
};

// Flags of `probelight run`. Empty strings mean "not given".
struct RunOptions {
  std::string source = "sim";         // sim | images | libcamera | recording
  std::string images;                 // folder or glob, for --source images
  std::string recording_dir;          // --recording: for --source recording
  std::string record_dir;             // --record: every camera frame goes here
  std::string display = "headless";   // headless | kms | window
  std::string button = "none";        // none | key
  std::string key_path = "-";         // stdin or a FIFO, for --button key
  long long frames = 300;             // 0 = until the source ends
  std::string out_dir = "out";
  std::string config_path;            // probelight.yaml
  std::string camera_path;            // --calibration: camera.yaml
  std::string camera_id;              // --camera-id: overrides camera.id
  std::string rig_path;               // rig.yaml
  std::string sim_env;                // overrides sim.env
  std::string sim_path;               // overrides sim.camera_path
  std::string model_path;             // --model: overrides object.model
  std::optional<int> save_every;      // overrides output.save_every
  std::string capture_dir;            // --capture: the last camera frame, camera.yaml and rig.yaml go here
  bool quiet = false;
  std::vector<std::string> warnings;  // flags that still work but are going (main prints them)
};

// Parses the flags after `probelight run`. Throws UsageError or
// HelpRequested, as do the other parse functions. A flag given twice: the
// last value wins (both are checked).
RunOptions parseRunOptions(const std::vector<std::string>& args);

// Flags of `probelight analyze`: one frame in, what the system sees out.
// All but config_path are required.
// --bracket FILE@EV: the same view as --frame, EV stops from its exposure.
struct BracketOption {
  std::string path;
  double ev = 0.0;
  // A recorded frame given without @EV: its EV is from its and --frame's
  // exposure metadata.
  bool ev_from_metadata = false;
};
// Bounds on --bracket (command_line.cpp says why).
inline constexpr double kMinBracketEv = 0.125;
inline constexpr double kMaxBracketEv = 24.0;
inline constexpr std::size_t kMaxBracketFrames = 16;

// A further view of the same rig for analyze (--frame given again), with
// the --bracket flags that follow it.
struct AnalyzeView {
  std::string frame_path;
  std::vector<BracketOption> brackets;
};
// At most this many --frame views: each is tracked and mapped in turn, and
// 40 of them is a glob gone wide, not a walk round the rig.
inline constexpr std::size_t kMaxAnalyzeViews = 16;

struct AnalyzeOptions {
  std::string frame_path;   // the camera frame (PNG, JPEG, ...)
  std::string camera_path;  // --calibration: camera.yaml of the camera that took it
  std::vector<std::string> warnings;  // flags that still work but are going (main prints them)
  std::string rig_path;     // rig.yaml
  std::string out_dir;      // analysis.json and the pictures go here
  std::string config_path;  // probelight.yaml (optional)
  std::vector<BracketOption> brackets;  // --bracket, repeatable: an exposure bracket
  // --frame again: further views, each with its own pose and brackets,
  // merged into one probe with the first (ibl/probe_accumulator.hpp). The
  // first --frame stays the reference: its exposure is the maps' unit, the
  // pictures show it.
  std::vector<AnalyzeView> more_views;
  // --no-white-ref: without a bracket, keep the ball's 8-bit map as it is
  // instead of giving its clipped highlights the light the tag's white
  // border says they hide (to compare the two).
  bool white_reference = true;
  // --no-post-ref: leave the border's light shared out by solid angle,
  // without the ball's post (rig.yaml post_radius, post_albedo) dividing it
  // between the clipped regions (ibl/post_reference.hpp).
  bool post_reference = true;
};

// Parses the flags after `probelight analyze`. Throws UsageError.
AnalyzeOptions parseAnalyzeOptions(const std::vector<std::string>& args);

// `probelight render`: analyze's flags, plus the virtual object to put into
// the frame, standing on the ground of W.
}  // namespace probelight
namespace probelight::model {
struct MeshModel;
}
namespace probelight {

struct RenderOptions {
  AnalyzeOptions frame;        // --frame, --calibration, --rig, --out, --config
  std::string object = "sphere";  // sphere | box | model
  double radius_m = 0.0;       // sphere: required
  glm::dvec3 box_size_m{0.0};  // box: --size X,Y,Z (required)
  std::string model_path;      // --model FILE: a glTF model (object "model")
  // Object "model" already in memory, in place of model_path's file: a
  // caller's own model (the accuracy tests' generated spheres and bowls).
  std::shared_ptr<const model::MeshModel> model;
  double scale = 1.0;          // model: --scale
  double yaw_deg = 0.0;        // box, model: turned about +Z
  glm::dvec2 at_w{0.0};        // --at X,Y: where it stands
  glm::dvec3 albedo{0.8};      // --albedo A or R,G,B in [0, 1]
};
RenderOptions parseRenderOptions(const std::vector<std::string>& args);

// Flags of `probelight calibrate-camera`: chessboard views in, camera.yaml
// out. All are required: a wrong board size finds no corners, and a default
// --out could overwrite the kiosk's calibration.
struct CalibrateCameraOptions {
  std::string images;       // glob of the views (quote it so the shell leaves it alone)
  int board_cols = 0;       // inner corners along a row (the 9 of --board 9x6)
  int board_rows = 0;       // inner corners along a column (the 6)
  double square_m = 0.0;    // edge of one square, metres
  std::string out_path;     // camera.yaml to write
};

// Parses the flags after `probelight calibrate-camera`. Throws UsageError.
CalibrateCameraOptions parseCalibrateCameraOptions(const std::vector<std::string>& args);

struct PrintTagOptions;
PrintTagOptions parsePrintTagOptions(const std::vector<std::string>& args);

// `probelight cameras` has no flags but -h.
struct CamerasOptions {};
CamerasOptions parseCamerasOptions(const std::vector<std::string>& args);

// The overview for `probelight`, `probelight --help`: the commands, one line
// each, and the exit statuses.
std::string usageText();

}  // namespace probelight
