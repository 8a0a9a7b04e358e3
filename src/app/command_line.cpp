#include "app/command_line.hpp"

#include <charconv>
#include <cmath>
#include <functional>
#include <map>
#include <optional>

namespace probelight {

namespace {

long long parseInteger(const std::string& flag, const std::string& text, long long min_value) {
  long long value = 0;
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(begin, end, value);
  if (ec != std::errc() || ptr != end || text.empty())
    throw UsageError("flag " + flag + ": expected a whole number, got '" + text + "'");
  if (value < min_value)
    throw UsageError("flag " + flag + ": must be at least " + std::to_string(min_value) + ", got " + text);
  return value;
}

void requireChoice(const std::string& flag, const std::string& value, const std::vector<std::string>& choices) {
  for (const auto& choice : choices)
    if (value == choice) return;
  std::string list;
  for (const auto& choice : choices) list += (list.empty() ? "" : ", ") + choice;
  throw UsageError("flag " + flag + ": unknown value '" + value + "' (choose " + list + ")");
}

using FlagSetter = std::function<void(const std::string& flag, const std::string& value)>;

// Walks `--flag value` and `--flag=value` pairs, calling the flag's setter.
// `switches` are flags without a value. `command` prefixes the unknown-flag
// message ("analyze: ..."), empty for run.
void parseFlags(const std::vector<std::string>& args, const std::map<std::string, FlagSetter>& valued,
                const std::map<std::string, std::function<void()>>& switches, const std::string& command) {
  for (size_t i = 0; i < args.size(); ++i) {
    std::string flag = args[i];
    std::optional<std::string> inline_value;
    if (auto eq = flag.find('='); flag.rfind("--", 0) == 0 && eq != std::string::npos) {
      inline_value = flag.substr(eq + 1);
      flag = flag.substr(0, eq);
    }
    if (auto on = switches.find(flag); on != switches.end() && !inline_value) {
      on->second();
      continue;
    }
    auto it = valued.find(flag);
    if (it == valued.end())
      throw UsageError((command.empty() ? "" : command + ": ") + "unknown flag '" + flag + "' (see probelight --help)");
    std::string value;
    if (inline_value) {
      value = *inline_value;
    } else {
      if (i + 1 >= args.size()) throw UsageError("flag " + flag + " needs a value");
      value = args[++i];
    }
    if (value.empty()) throw UsageError("flag " + flag + " needs a value");
    it->second(flag, value);
  }
}

}  // namespace

RunOptions parseRunOptions(const std::vector<std::string>& args) {
  RunOptions options;
  const std::map<std::string, FlagSetter> valued = {
      {"--source", [&](auto& f, auto& v) { requireChoice(f, v, {"sim", "images", "libcamera"}); options.source = v; }},
      {"--images", [&](auto&, auto& v) { options.images = v; }},
      {"--display", [&](auto& f, auto& v) { requireChoice(f, v, {"headless", "kms"}); options.display = v; }},
      {"--button", [&](auto& f, auto& v) { requireChoice(f, v, {"none", "key", "gpio"}); options.button = v; }},
      {"--key-input", [&](auto&, auto& v) { options.key_path = v; }},
      {"--frames", [&](auto& f, auto& v) { options.frames = parseInteger(f, v, 0); }},
      {"--out", [&](auto&, auto& v) { options.out_dir = v; }},
      {"--config", [&](auto&, auto& v) { options.config_path = v; }},
      {"--camera", [&](auto&, auto& v) { options.camera_path = v; }},
      {"--rig", [&](auto&, auto& v) { options.rig_path = v; }},
      {"--env", [&](auto&, auto& v) { options.sim_env = v; }},
      {"--path", [&](auto&, auto& v) { options.sim_path = v; }},
      {"--save-every", [&](auto& f, auto& v) { options.save_every = static_cast<int>(parseInteger(f, v, 0)); }},
  };
  parseFlags(args, valued, {{"--quiet", [&] { options.quiet = true; }}}, "");
  if (options.source == "images" && options.images.empty())
    throw UsageError("flag --source images needs --images FOLDER_OR_GLOB");
  if (options.source == "images" && options.camera_path.empty())
    throw UsageError("flag --source images needs --camera camera.yaml (the calibration of the camera that took them)");
  if (options.source == "images" && options.rig_path.empty())
    throw UsageError("flag --source images needs --rig rig.yaml");
  if (options.source == "libcamera" && options.camera_path.empty())
    throw UsageError("flag --source libcamera needs --camera camera.yaml (its calibration, at the size to stream)");
  if (options.source == "libcamera" && options.rig_path.empty())
    throw UsageError("flag --source libcamera needs --rig rig.yaml");
  return options;
}

namespace {

// Comma-separated finite numbers, exactly `count` of them (or 1 when
// `one_for_all`: the same value for every component).
std::vector<double> parseNumberList(const std::string& flag, const std::string& text, std::size_t count,
                                    bool one_for_all, const std::string& what) {
  std::vector<double> values;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::string part = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    double value = 0.0;
    auto [ptr, ec] = std::from_chars(part.data(), part.data() + part.size(), value);
    if (part.empty() || ec != std::errc() || ptr != part.data() + part.size() || !std::isfinite(value))
      throw UsageError("flag " + flag + ": expected " + what + ", got '" + text + "'");
    values.push_back(value);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (one_for_all && values.size() == 1) values.assign(count, values[0]);
  if (values.size() != count) throw UsageError("flag " + flag + ": expected " + what + ", got '" + text + "'");
  return values;
}

}  // namespace

namespace {

// FILE@EV, the EV after the last '@' (a file name may hold one too).
BracketOption parseBracket(const std::string& flag, const std::string& text) {
  const std::size_t at = text.rfind('@');
  if (at == std::string::npos || at == 0 || at + 1 == text.size())
    throw UsageError("flag " + flag + ": expected FILE@EV (the same view, EV stops from --frame's exposure, e.g. "
                     "under3.png@-3), got '" + text + "'");
  BracketOption bracket;
  bracket.path = text.substr(0, at);
  bracket.ev = parseNumberList(flag, text.substr(at + 1), 1, false, "FILE@EV with EV a number of stops")[0];
  if (std::abs(bracket.ev) > 24.0 || bracket.ev == 0.0)
    throw UsageError("flag " + flag + ": EV must be non-zero and within +-24 stops, got '" + text + "'");
  return bracket;
}

}  // namespace

AnalyzeOptions parseAnalyzeOptions(const std::vector<std::string>& args) {
  AnalyzeOptions options;
  auto into = [](std::string& field) { return [&field](const std::string&, const std::string& value) { field = value; }; };
  parseFlags(args,
             {{"--frame", into(options.frame_path)},
              {"--camera", into(options.camera_path)},
              {"--rig", into(options.rig_path)},
              {"--out", into(options.out_dir)},
              {"--config", into(options.config_path)},
              {"--bracket", [&](auto& f, auto& v) { options.brackets.push_back(parseBracket(f, v)); }}},
             {{"--no-white-ref", [&] { options.white_reference = false; }},
              {"--no-post-ref", [&] { options.post_reference = false; }}},
             "analyze");
  // No defaults for these: analysing a frame with some other camera's
  // calibration, or writing over someone's folder, gives plausible nonsense.
  if (options.frame_path.empty()) throw UsageError("analyze needs --frame FILE (the camera frame to analyse)");
  if (options.camera_path.empty()) throw UsageError("analyze needs --camera camera.yaml (the calibration of the camera that took it)");
  if (options.rig_path.empty()) throw UsageError("analyze needs --rig rig.yaml");
  if (options.out_dir.empty()) throw UsageError("analyze needs --out DIR (where analysis.json and the pictures go)");
  return options;
}


RenderOptions parseRenderOptions(const std::vector<std::string>& args) {
  RenderOptions options;
  auto into = [](std::string& field) { return [&field](const std::string&, const std::string& value) { field = value; }; };
  bool have_size = false;
  parseFlags(args,
             {{"--frame", into(options.frame.frame_path)},
              {"--camera", into(options.frame.camera_path)},
              {"--rig", into(options.frame.rig_path)},
              {"--out", into(options.frame.out_dir)},
              {"--config", into(options.frame.config_path)},
              {"--bracket", [&](auto& f, auto& v) { options.frame.brackets.push_back(parseBracket(f, v)); }},
              {"--object", [&](auto& f, auto& v) { requireChoice(f, v, {"sphere", "box"}); options.object = v; }},
              {"--radius",
               [&](auto& f, auto& v) {
                 options.radius_m = parseNumberList(f, v, 1, false, "a radius in metres, e.g. 0.03")[0];
                 if (!(options.radius_m > 0.0)) throw UsageError("flag " + f + ": the radius must be > 0, got '" + v + "'");
               }},
              {"--size",
               [&](auto& f, auto& v) {
                 const auto s = parseNumberList(f, v, 3, false, "the box's edges X,Y,Z in metres, e.g. 0.05,0.04,0.06");
                 if (!(s[0] > 0.0 && s[1] > 0.0 && s[2] > 0.0))
                   throw UsageError("flag " + f + ": every edge must be > 0, got '" + v + "'");
                 options.box_size_m = {s[0], s[1], s[2]};
                 have_size = true;
               }},
              {"--yaw", [&](auto& f, auto& v) { options.yaw_deg = parseNumberList(f, v, 1, false, "degrees")[0]; }},
              {"--at",
               [&](auto& f, auto& v) {
                 const auto p = parseNumberList(f, v, 2, false, "X,Y in metres on the ground of the tag's frame");
                 options.at_w = {p[0], p[1]};
               }},
              {"--albedo",
               [&](auto& f, auto& v) {
                 const auto a = parseNumberList(f, v, 3, true, "A or R,G,B in [0, 1]");
                 for (double c : a)
                   if (c < 0.0 || c > 1.0) throw UsageError("flag " + f + ": albedo must be in [0, 1], got '" + v + "'");
                 options.albedo = {a[0], a[1], a[2]};
               }}},
             {{"--no-white-ref", [&] { options.frame.white_reference = false; }},
              {"--no-post-ref", [&] { options.frame.post_reference = false; }}},
             "render");
  if (options.frame.frame_path.empty()) throw UsageError("render needs --frame FILE (the camera frame)");
  if (options.frame.camera_path.empty()) throw UsageError("render needs --camera camera.yaml (the calibration of the camera that took it)");
  if (options.frame.rig_path.empty()) throw UsageError("render needs --rig rig.yaml");
  if (options.frame.out_dir.empty()) throw UsageError("render needs --out DIR (where composite.png and analysis.json go)");
  if (options.object == "sphere" && options.radius_m == 0.0) throw UsageError("render needs --radius METRES for a sphere");
  if (options.object == "box" && !have_size) throw UsageError("render needs --size X,Y,Z (metres) for a box");
  if (options.object == "sphere" && have_size) throw UsageError("flag --size: only for --object box");
  return options;
}

namespace {

// --board COLSxROWS, inner corners. OpenCV's detector needs at least 3 each
// way (it throws below that), so 1x1 or 2x5 is refused here with the flag's name.
void parseBoard(const std::string& flag, const std::string& text, int& cols, int& rows) {
  const auto x = text.find_first_of("xX");
  const std::string bad = "flag " + flag + ": expected inner corners as COLSxROWS (e.g. 9x6), got '" + text + "'";
  if (x == std::string::npos) throw UsageError(bad);
  auto whole = [&](const std::string& part, int& value) {
    auto [ptr, ec] = std::from_chars(part.data(), part.data() + part.size(), value);
    if (part.empty() || ec != std::errc() || ptr != part.data() + part.size()) throw UsageError(bad);
  };
  whole(text.substr(0, x), cols);
  whole(text.substr(x + 1), rows);
  if (cols < 3 || rows < 3)
    throw UsageError("flag " + flag + ": the board needs at least 3x3 inner corners, got '" + text + "'");
}

// --square in metres. Above 1 m is almost surely millimetres typed as metres
// (25 for 0.025); the focal length would not care, but the saved poses would.
double parseSquare(const std::string& flag, const std::string& text) {
  double value = 0.0;
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(value))
    throw UsageError("flag " + flag + ": expected the square's edge in metres (e.g. 0.025), got '" + text + "'");
  if (value <= 0.0 || value > 1.0)
    throw UsageError("flag " + flag + ": the square's edge must be in (0, 1] metres, got '" + text + "'");
  return value;
}

}  // namespace

CalibrateCameraOptions parseCalibrateCameraOptions(const std::vector<std::string>& args) {
  CalibrateCameraOptions options;
  parseFlags(args,
             {{"--images", [&](auto&, auto& v) { options.images = v; }},
              {"--board", [&](auto& f, auto& v) { parseBoard(f, v, options.board_cols, options.board_rows); }},
              {"--square", [&](auto& f, auto& v) { options.square_m = parseSquare(f, v); }},
              {"--out", [&](auto&, auto& v) { options.out_path = v; }}},
             {}, "calibrate-camera");
  if (options.images.empty()) throw UsageError("calibrate-camera needs --images GLOB (the chessboard views)");
  if (options.board_cols == 0) throw UsageError("calibrate-camera needs --board COLSxROWS (inner corners, e.g. 9x6)");
  if (options.square_m == 0.0) throw UsageError("calibrate-camera needs --square METRES (a square's edge, e.g. 0.025)");
  if (options.out_path.empty()) throw UsageError("calibrate-camera needs --out camera.yaml");
  return options;
}

std::string usageText() {
  return R"(probelight: image-based lighting for an AR kiosk (mirror ball + AprilTag)

usage:
  probelight run [flags]       run the kiosk: frames in, composited frames out
  probelight analyze --frame F --camera camera.yaml --rig rig.yaml --out DIR [--config probelight.yaml]
                               one frame in: DIR/analysis.json (tag, pose, ball, irradiance, timings)
                               and pictures (overlay.png, ball.png, reflection_cross.png, diffuse_cross.png)
      [--bracket FILE@EV]...   the same view EV stops shorter (e.g. under3.png@-3), merged into HDR light
      [--no-white-ref]         without a bracket, do not use the tag's white border to restore clipped light
      [--no-post-ref]          nor the ball's post (rig.yaml post_radius, post_albedo) to divide that light
  probelight render --frame F --camera camera.yaml --rig rig.yaml --out DIR --object sphere --radius R
                    [--at X,Y] [--albedo A|R,G,B] [--config probelight.yaml]
  probelight render ... --object box --size X,Y,Z [--yaw DEG]   (and analyze's --bracket, --no-white-ref, --no-post-ref)
                               a virtual object put into one frame, lit by what its ball shows and
                               casting its shadow on the real ground: DIR/composite.png and analysis.json
  probelight calibrate-camera --images GLOB --board COLSxROWS --square METRES --out camera.yaml
                               chessboard views in, camera.yaml out; prints the RMS and per-view
                               reprojection errors and why each rejected view was rejected
  probelight --help | --version

run flags:
  --source sim|images|libcamera
                               frame source (default sim: the simulated world; libcamera: the camera)
  --images FOLDER_OR_GLOB      files to replay with --source images
  --camera camera.yaml         camera calibration (sim: overrides the simulated camera)
  --rig rig.yaml               tag and mirror-ball geometry (sim: overrides the simulated rig)
  --config probelight.yaml     pipeline settings (see board/probelight.yaml)
  --display headless|kms       headless EGL on Mesa, frames written as PNG; or fullscreen on the
                               board's screen through DRM/KMS (probelight.yaml's display section)
  --button none|key|gpio       recalibration button (key: lines on stdin or a FIFO; gpio: the board's
                               button, probelight.yaml's button section)
  --key-input PATH             where --button key reads ('-' = stdin, default)
  --frames N                   frames to process, 0 = until the source ends (default 300)
  --save-every K               write every K-th composited frame as PNG, 0 = none (default 1)
  --out DIR                    output folder for frames and report.json (default out)
  --env NAME|FILE              sim: studio, sun_sky, overcast, coloured_wall, uniform, or an .exr/.hdr file
  --path NAME                  sim: camera path: static, orbit, slow_wobble, random
  --quiet                      no per-frame status lines

calibrate-camera flags:
  --images GLOB                the views, e.g. 'captures/board_*.png' (quoted)
  --board COLSxROWS            inner corners of the chessboard, e.g. 9x6
  --square METRES              edge of one square, e.g. 0.025
  --out camera.yaml            where the calibration goes

exit status: 0 ok, 1 runtime failure, 2 bad flags or configuration
             (calibrate-camera: also no matching files or too few usable views),
             3 (analyze, render) the tag or the ball was not found: analysis.json says why.
)";
}

}  // namespace probelight
