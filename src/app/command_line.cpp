#include "app/command_line.hpp"
#include "capture/frame_recording.hpp"
#include "app/print_tag.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <limits>
#include <cmath>
#include <deque>
#include <functional>
#include <map>
#include <optional>

namespace probelight {

namespace {

// The values: every flag's value is a string to CLI11; these turn it into
// the option's type, with a message that names the flag.

long long parseInteger(const std::string& flag, const std::string& text, long long min_value,
                       long long max_value = std::numeric_limits<long long>::max()) {
  long long value = 0;
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(begin, end, value);
  if (ec != std::errc() || ptr != end || text.empty())
    throw UsageError("flag " + flag + ": expected a whole number, got '" + text + "'");
  if (value < min_value)
    throw UsageError("flag " + flag + ": must be at least " + std::to_string(min_value) + ", got " + text);
  if (value > max_value)
    throw UsageError("flag " + flag + ": must be at most " + std::to_string(max_value) + ", got " + text);
  return value;
}

void requireChoice(const std::string& flag, const std::string& value, const std::vector<std::string>& choices) {
  for (const auto& choice : choices)
    if (value == choice) return;
  std::string list;
  for (const auto& choice : choices) list += (list.empty() ? "" : ", ") + choice;
  throw UsageError("flag " + flag + ": unknown value '" + value + "' (choose " + list + ")");
}

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

// FILE@EV, the EV after the last '@' (a file name may hold one too).
BracketOption parseBracket(const std::string& flag, const std::string& text) {
  const std::size_t at = text.rfind('@');
  // A recorded frame says its own exposure: its EV comes from the two
  // frames' metadata (analyze checks it then).
  if (at == std::string::npos && isRecordedFramePath(text)) return {text, 0.0, true};
  if (at == std::string::npos || at == 0 || at + 1 == text.size())
    throw UsageError("flag " + flag + ": expected FILE@EV (the same view, EV stops from --frame's exposure, e.g. "
                     "under3.png@-3; a recorded frame's .json alone), got '" + text + "'");
  BracketOption bracket;
  bracket.path = text.substr(0, at);
  bracket.ev = parseNumberList(flag, text.substr(at + 1), 1, false, "FILE@EV with EV a number of stops")[0];
  // Below an eighth of a stop a frame adds no range to --frame's (cameras
  // step exposure in thirds); 1e-300 passed a "non-zero" check.
  if (std::abs(bracket.ev) > kMaxBracketEv || std::abs(bracket.ev) < kMinBracketEv)
    throw UsageError("flag " + flag + ": EV must be 0.125 to 24 stops either way from --frame's, got '" + text + "'");
  return bracket;
}

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

// The commands: their one-line summary (the overview and the top of their
// --help) and the exit statuses their --help ends with.
struct Command {
  std::string name;
  std::string summary;
  std::string exit_status;
};

const Command kRun{"run", "run the kiosk: frames in, composited frames out",
                   "exit status: 0 ok, 1 runtime failure, 2 bad flags or configuration"};
const Command kAnalyze{"analyze",
                       "one frame in: DIR/analysis.json (tag, pose, ball, irradiance, timings) and pictures\n"
                       "(overlay.png, ball.png, reflection_cross.png, diffuse_cross.png)",
                       "exit status: 0 ok, 1 runtime failure, 2 bad flags or configuration,\n"
                       "             3 the tag or the ball was not found: analysis.json says why"};
const Command kRender{"render",
                      "a virtual object put into one frame, lit by what its ball shows and casting its shadow\n"
                      "on the real ground: DIR/composite.png and analysis.json",
                      kAnalyze.exit_status};
const Command kCalibrateCamera{"calibrate-camera",
                               "chessboard views in, camera.yaml out; prints the RMS and per-view reprojection\n"
                               "errors and why each rejected view was rejected",
                               "exit status: 0 ok, 1 runtime failure,\n"
                               "             2 bad flags, no matching files or too few usable views"};

const Command kCameras{"cameras",
                       "lists the cameras libcamera finds: each one's id (for --camera-id or camera.id), model,\n"
                       "and the pixel formats and sizes its viewfinder stream offers",
                       "exit status: 0 ok (no camera is said in one line), 1 libcamera did not start, 2 bad flags"};

const Command kPrintTag{"print-tag",
                        "the rig's AprilTag as a PNG to print, to scale: rig.yaml's family, id and size, with a\n"
                        "50 mm scale bar; the file says its resolution, so print it at 100% (actual size)",
                        "exit status: 0 ok, 1 the file could not be written, 2 bad flags or rig.yaml"};

using FlagSetter = std::function<void(const std::string& flag, const std::string& value)>;

// A flag with a value. The setter gets the flag's long name (for messages)
// and each value given, in the order given: a repeated flag's last value
// wins, and every value is checked.
struct ValuedFlag {
  std::string names;        // "--frames", or with a short name "-n,--frames"
  std::string value_name;   // the value in the help: "N", "camera.yaml"
  std::string description;  // one line, defaults and choices included
  FlagSetter set;
  bool repeatable = false;  // --bracket: each value adds one (the help says so)
};

// A flag without a value.
struct Switch {
  std::string names;
  std::string description;
  std::function<void()> set;
};

std::string longName(const std::string& names) {
  const std::size_t at = names.find("--");
  return at == std::string::npos ? names : names.substr(at, names.find(',', at) - at);
}

std::string oneLine(std::string text) {
  for (char& c : text)
    if (c == '\n') c = ' ';
  return text;
}


// --camera named the calibration file until --camera-id came: it is kept
// for one release as --calibration's alias, saying so on stderr (the
// warning goes to `warnings`; main prints it).
ValuedFlag deprecatedCameraFlag(std::string& calibration_path, std::vector<std::string>& warnings) {
  return {"--camera", "camera.yaml", "deprecated: --calibration's old name, kept for this release",
          [&calibration_path, &warnings](const std::string&, const std::string& value) {
            calibration_path = value;
            const std::string warning =
                "flag --camera is deprecated: it is --calibration now (the camera itself is --camera-id); "
                "the old name goes in the next release";
            if (warnings.empty() || warnings.back() != warning) warnings.push_back(warning);
          }};
}

// CLI11 gives the structure (--flag value, --flag=value, short names, -h and
// --help with its text); the setters convert, with messages naming the flag.
// Any usage error is one UsageError line, "<command>: ..." or "flag --X ...";
// -h or --help throws HelpRequested with the command's help.
void parseFlagsAsGiven(const std::vector<std::string>& args, const Command& command, const std::vector<ValuedFlag>& valued,
                       const std::vector<Switch>& switches) {
  CLI::App app("probelight " + command.name + ": " + command.summary + "\n", "probelight " + command.name);
  app.option_defaults()->group("flags");
  app.set_help_flag("-h,--help", "print this help and exit");
  app.allow_extras();  // an unknown flag: our message below, not CLI11's
  app.footer(command.exit_status);
  app.get_formatter()->column_width(33);
  app.get_formatter()->label("OPTIONS", "flags");
  app.get_formatter()->label("Usage", "usage");
  std::vector<CLI::Option*> valued_options;
  for (const ValuedFlag& flag : valued)
    valued_options.push_back(
        app.add_option(flag.names, CLI::callback_t{}, flag.description + (flag.repeatable ? "; repeatable" : ""))
            ->option_text(flag.value_name)
            ->allow_extra_args(false)  // one value per flag: `--bracket a@-1 b@-2` is not two brackets
            ->multi_option_policy(flag.repeatable ? CLI::MultiOptionPolicy::TakeAll : CLI::MultiOptionPolicy::TakeLast));
  std::vector<CLI::Option*> switch_options;
  for (const Switch& flag : switches) switch_options.push_back(app.add_flag(flag.names, flag.description));

  const std::string prefix = command.name + ": ";
  const std::string see_help = " (see probelight " + command.name + " --help)";
  // `--flag=` would make CLI11 take the next argument as the value, and
  // `--quiet=no` would set --quiet: both are errors here.
  for (const std::string& arg : args) {
    if (arg == "--") break;
    const std::size_t eq = arg.find('=');
    if (arg.rfind("--", 0) != 0 || eq == std::string::npos) continue;
    const std::string name = arg.substr(0, eq);
    for (const ValuedFlag& flag : valued)
      if (longName(flag.names) == name && eq + 1 == arg.size()) throw UsageError("flag " + name + " needs a value");
    for (const Switch& flag : switches)
      if (longName(flag.names) == name) throw UsageError("flag " + name + " takes no value" + see_help);
  }

  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them last first
  try {
    app.parse(reversed);
  } catch (const CLI::CallForHelp&) {
    throw HelpRequested{app.help()};
  } catch (const CLI::ArgumentMismatch& error) {
    // The one CLI11 raises here: the last flag has no value left
    // ("--frames: 1 required  missing").
    const std::string what = error.what();
    const std::string name = what.substr(0, what.find(':'));
    for (const ValuedFlag& flag : valued)
      if (longName(flag.names) == name) throw UsageError("flag " + name + " needs a value");
    throw UsageError(prefix + oneLine(what) + see_help);
  } catch (const CLI::ParseError& error) {
    throw UsageError(prefix + oneLine(error.what()) + see_help);
  }
  if (const std::vector<std::string> extras = app.remaining(); !extras.empty()) {
    const std::string& extra = extras.front();
    if (extra.size() > 1 && extra[0] == '-')
      throw UsageError(prefix + "unknown flag '" + extra.substr(0, extra.find('=')) + "'" + see_help);
    throw UsageError(prefix + "unexpected argument '" + extra + "' (flags take one value each)" + see_help);
  }
  for (std::size_t i = 0; i < valued.size(); ++i) {
    const std::string name = longName(valued[i].names);
    for (const std::string& value : valued_options[i]->results()) {
      if (value.empty()) throw UsageError("flag " + name + " needs a value");
      valued[i].set(name, value);
    }
  }
  for (std::size_t i = 0; i < switches.size(); ++i)
    if (switch_options[i]->count() > 0) switches[i].set();
}

void parseFlags(const std::vector<std::string>& args, const Command& command, const std::vector<ValuedFlag>& valued,
                const std::vector<Switch>& switches) {
  try {
    parseFlagsAsGiven(args, command, valued, switches);
  } catch (const UsageError& error) {
    throw UsageError(printable(error.what()));
  }
}

}  // namespace

std::string printable(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (byte < 0x20 || byte == 0x7f) {
      static const char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[byte >> 4];
      out += kHex[byte & 15];
    } else {
      out += c;
    }
  }
  return out;
}

RunOptions parseRunOptions(const std::vector<std::string>& args) {
  RunOptions options;
  auto into = [](std::string& field) { return [&field](const std::string&, const std::string& value) { field = value; }; };
  parseFlags(
      args, kRun,
      {{"--source", "sim|images|libcamera|recording",
        "frame source (default sim: the simulated world; images: files; libcamera: the camera; recording: "
        "frames made by --record, as the camera gave them)",
        [&](auto& f, auto& v) { requireChoice(f, v, {"sim", "images", "libcamera", "recording"}); options.source = v; }},
       {"--images", "FOLDER_OR_GLOB", "files to replay with --source images", into(options.images)},
       {"--recording", "DIR", "the recording to replay with --source recording (its camera.yaml and rig.yaml are the defaults)",
        into(options.recording_dir)},
       {"--record", "DIR",
        "write every camera frame as it came (its planes, exposure, gain, timestamp, format) to DIR, with "
        "camera.yaml and rig.yaml, for --source recording and analyze",
        into(options.record_dir)},
       {"--calibration", "camera.yaml", "camera calibration (sim: overrides the simulated camera)",
        into(options.camera_path)},
       deprecatedCameraFlag(options.camera_path, options.warnings),
       {"--camera-id", "ID",
        "which camera, as probelight cameras lists it (--source libcamera; overrides camera.id, default the first)",
        into(options.camera_id)},
       {"--rig", "rig.yaml", "tag and mirror-ball geometry (sim: overrides the simulated rig)", into(options.rig_path)},
       {"-c,--config", "probelight.yaml", "pipeline settings (see board/probelight.yaml)", into(options.config_path)},
       {"--display", "headless|kms|window",
        "headless (default: Mesa's EGL, frames written as PNG), kms (fullscreen on the board's screen) or window "
        "(a desktop window: R or space recalibrates, hold R for the stored lighting, S saves, Q or Esc quits)",
        [&](auto& f, auto& v) { requireChoice(f, v, {"headless", "kms", "window"}); options.display = v; }},
       {"--button", "none|key|gpio",
        "recalibration button (default none; key: lines on stdin or a FIFO; gpio: the board's button)",
        [&](auto& f, auto& v) { requireChoice(f, v, {"none", "key", "gpio"}); options.button = v; }},
       {"--key-input", "PATH", "where --button key reads ('-' = stdin, default)", into(options.key_path)},
       {"-n,--frames", "N", "frames to process, 0 = until the source ends (default 300)",
        [&](auto& f, auto& v) { options.frames = parseInteger(f, v, 0); }},
       {"--save-every", "K", "write every K-th composited frame as PNG, 0 = none (default 1)",
        [&](auto& f, auto& v) { options.save_every = static_cast<int>(parseInteger(f, v, 0, std::numeric_limits<int>::max())); }},
       {"-o,--out", "DIR", "output folder for frames and report.json (default out)", into(options.out_dir)},
       {"--capture", "DIR",
        "keep the last camera frame with its camera.yaml and rig.yaml in DIR (for analyze, render)",
        into(options.capture_dir)},
       {"--env", "NAME|FILE", "sim: studio, sun_sky, sunrise, night_street, overcast, coloured_wall, uniform, or an .exr/.hdr file",
        into(options.sim_env)},
       {"--path", "NAME", "sim: camera path: static, orbit, slow_wobble, random, hand_held_sweep, pan", into(options.sim_path)},
       {"--model", "FILE", "a glTF 2.0 model (.gltf, .glb) to show instead of the sphere (overrides object.model)",
        into(options.model_path)}},
      {{"-q,--quiet", "no per-frame status lines", [&] { options.quiet = true; }}});
  if (options.source == "images" && options.images.empty())
    throw UsageError("flag --source images needs --images FOLDER_OR_GLOB");
  if (options.source == "images" && options.camera_path.empty())
    throw UsageError("flag --source images needs --calibration camera.yaml (the calibration of the camera that took them)");
  if (options.source == "images" && options.rig_path.empty())
    throw UsageError("flag --source images needs --rig rig.yaml");
  if (options.source == "recording") {
    if (options.recording_dir.empty()) throw UsageError("flag --source recording needs --recording DIR (made by --record)");
    // A recording carries the calibration and rig it was seen through.
    if (options.camera_path.empty()) options.camera_path = (std::filesystem::path(options.recording_dir) / "camera.yaml").string();
    if (options.rig_path.empty()) options.rig_path = (std::filesystem::path(options.recording_dir) / "rig.yaml").string();
  }
  if (!options.recording_dir.empty() && options.source != "recording")
    throw UsageError("flag --recording: only with --source recording");
  if (!options.record_dir.empty() && options.record_dir == options.recording_dir)
    throw UsageError("flag --record: not the folder being replayed (--recording)");
  if (options.source == "libcamera" && options.camera_path.empty())
    throw UsageError("flag --source libcamera needs --calibration camera.yaml (its calibration, at the size to stream)");
  if (options.source == "libcamera" && options.rig_path.empty())
    throw UsageError("flag --source libcamera needs --rig rig.yaml");
  return options;
}

namespace {

// analyze's flags, render's too: the frame, its calibration, the rig, where
// the results go, and how the light is read.
std::vector<ValuedFlag> frameFlags(AnalyzeOptions& options, const std::string& out_description) {
  auto into = [](std::string& field) { return [&field](const std::string&, const std::string& value) { field = value; }; };
  return {{"-f,--frame", "FILE",
           "the camera frame: PNG, JPEG, ..., or a recorded one (DIR/frame_NNNNNN.json from run --record) "
           "(required); again for more views of the same rig, each with its own pose and the --bracket flags "
           "after it, merged into one probe",
           [&options](const std::string&, const std::string& value) {
             if (options.frame_path.empty())
               options.frame_path = value;
             else
               options.more_views.push_back({value, {}});
           },
           true},
          {"--calibration", "camera.yaml", "the calibration of the camera that took it (required)",
           into(options.camera_path)},
          deprecatedCameraFlag(options.camera_path, options.warnings),
          {"--rig", "rig.yaml", "tag and mirror-ball geometry (required)", into(options.rig_path)},
          {"-o,--out", "DIR", out_description + " (required)", into(options.out_dir)},
          {"-c,--config", "probelight.yaml", "pipeline settings (optional, see board/probelight.yaml)",
           into(options.config_path)},
          {"--bracket", "FILE@EV",
           "the same view EV stops from --frame's exposure, e.g. under3.png@-3, merged into HDR light (a recorded "
           "frame's EV comes from its metadata)",
           [&options](auto& f, auto& v) { options.brackets.push_back(parseBracket(f, v)); }, true}};
}

std::vector<Switch> lightSwitches(AnalyzeOptions& options) {
  return {{"--no-white-ref", "without a bracket, do not use the tag's white border to restore clipped light",
           [&options] { options.white_reference = false; }},
          {"--no-post-ref", "nor the ball's post (rig.yaml post_radius, post_albedo) to divide that light",
           [&options] { options.post_reference = false; }}};
}

}  // namespace

// A recorded frame's folder holds the calibration and rig it was seen
// through (run --record): the defaults for --calibration and --rig.
static void defaultToTheRecordingsFiles(AnalyzeOptions& options) {
  if (options.frame_path.empty() || !isRecordedFramePath(options.frame_path)) return;
  const std::filesystem::path dir = std::filesystem::path(options.frame_path).parent_path();
  if (options.camera_path.empty()) options.camera_path = (dir / "camera.yaml").string();
  if (options.rig_path.empty()) options.rig_path = (dir / "rig.yaml").string();
}

// Each bracket frame is decoded and kept while merging: 40 of them is a
// mistake (a glob gone wide), not a bracket; the kiosk's own has 5.
static void checkBracketCount(const AnalyzeOptions& options) {
  auto check = [](std::size_t count) {
    if (count > kMaxBracketFrames)
      throw UsageError("flag --bracket: at most " + std::to_string(kMaxBracketFrames) + " bracket frames, got " +
                       std::to_string(count));
  };
  check(options.brackets.size());
  for (const AnalyzeView& view : options.more_views) check(view.brackets.size());
  if (options.more_views.size() + 1 > kMaxAnalyzeViews)
    throw UsageError("flag --frame: at most " + std::to_string(kMaxAnalyzeViews) + " views, got " +
                     std::to_string(options.more_views.size() + 1));
}

// The flags are parsed flag by flag, so which --frame a --bracket follows
// is read from the arguments' order: each --bracket belongs to the last
// --frame before it (one before any --frame, to the first).
static void giveBracketsToTheirFrames(const std::vector<std::string>& args, AnalyzeOptions& options) {
  if (options.more_views.empty()) return;
  std::vector<std::size_t> owner;  // per --bracket in order: 0 the first frame, i view i
  std::size_t frames_seen = 0;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "--") break;
    const bool frame_flag = arg == "-f" || arg == "--frame";
    const bool bracket_flag = arg == "--bracket";
    if (frame_flag || arg.rfind("--frame=", 0) == 0 || (arg.size() > 2 && arg.rfind("-f", 0) == 0 && arg[1] != '-'))
      ++frames_seen;
    else if (bracket_flag || arg.rfind("--bracket=", 0) == 0)
      owner.push_back(frames_seen == 0 ? 0 : frames_seen - 1);
    if (frame_flag || bracket_flag) ++i;  // its value
  }
  if (owner.size() != options.brackets.size()) return;  // cannot tell: all stay with the first
  std::vector<BracketOption> first;
  for (std::size_t b = 0; b < owner.size(); ++b) {
    if (owner[b] == 0)
      first.push_back(options.brackets[b]);
    else if (owner[b] - 1 < options.more_views.size())
      options.more_views[owner[b] - 1].brackets.push_back(options.brackets[b]);
  }
  options.brackets = std::move(first);
}

AnalyzeOptions parseAnalyzeOptions(const std::vector<std::string>& args) {
  AnalyzeOptions options;
  parseFlags(args, kAnalyze, frameFlags(options, "where analysis.json and the pictures go"), lightSwitches(options));
  giveBracketsToTheirFrames(args, options);
  defaultToTheRecordingsFiles(options);
  // No defaults for these: analysing a frame with some other camera's
  // calibration, or writing over someone's folder, gives plausible nonsense.
  if (options.frame_path.empty()) throw UsageError("analyze needs --frame FILE (the camera frame to analyse)");
  if (options.camera_path.empty()) throw UsageError("analyze needs --calibration camera.yaml (the calibration of the camera that took it)");
  if (options.rig_path.empty()) throw UsageError("analyze needs --rig rig.yaml");
  if (options.out_dir.empty()) throw UsageError("analyze needs --out DIR (where analysis.json and the pictures go)");
  checkBracketCount(options);
  return options;
}

RenderOptions parseRenderOptions(const std::vector<std::string>& args) {
  RenderOptions options;
  bool have_size = false, have_scale = false;
  std::string object_flag;
  std::vector<ValuedFlag> valued = frameFlags(options.frame, "where composite.png and analysis.json go");
  const std::vector<ValuedFlag> object_flags = {
      {"--object", "sphere|box", "the virtual object (default sphere; --model FILE for a model)",
       [&](auto& f, auto& v) {
         requireChoice(f, v, {"sphere", "box"});
         object_flag = v;
       }},
      {"--radius", "METRES", "sphere: its radius (required for a sphere)",
       [&](auto& f, auto& v) {
         options.radius_m = parseNumberList(f, v, 1, false, "a radius in metres, e.g. 0.03")[0];
         if (!(options.radius_m > 0.0)) throw UsageError("flag " + f + ": the radius must be > 0, got '" + v + "'");
       }},
      {"--size", "X,Y,Z", "box: its edges in metres (required for a box)",
       [&](auto& f, auto& v) {
         const auto s = parseNumberList(f, v, 3, false, "the box's edges X,Y,Z in metres, e.g. 0.05,0.04,0.06");
         if (!(s[0] > 0.0 && s[1] > 0.0 && s[2] > 0.0))
           throw UsageError("flag " + f + ": every edge must be > 0, got '" + v + "'");
         options.box_size_m = {s[0], s[1], s[2]};
         have_size = true;
       }},
      {"--model", "FILE", "a glTF 2.0 model (.gltf, .glb) with its own materials, instead of a sphere or box",
       [&](auto&, auto& v) {
         options.model_path = v;
         options.object = "model";
       }},
      {"--scale", "S", "model: its size times S (default 1; glTF is in metres)",
       [&](auto& f, auto& v) {
         options.scale = parseNumberList(f, v, 1, false, "a factor, e.g. 0.5")[0];
         if (!(options.scale > 0.0)) throw UsageError("flag " + f + ": the scale must be > 0, got '" + v + "'");
         have_scale = true;
       }},
      {"--yaw", "DEG", "box, model: turned about the tag's +Z (default 0)",
       [&](auto& f, auto& v) { options.yaw_deg = parseNumberList(f, v, 1, false, "degrees")[0]; }},
      {"--at", "X,Y", "where it stands, metres on the ground of the tag's frame (default 0,0)",
       [&](auto& f, auto& v) {
         const auto p = parseNumberList(f, v, 2, false, "X,Y in metres on the ground of the tag's frame");
         options.at_w = {p[0], p[1]};
       }},
      {"--albedo", "A|R,G,B", "its colour, each in [0, 1] (default 0.8)",
       [&](auto& f, auto& v) {
         const auto a = parseNumberList(f, v, 3, true, "A or R,G,B in [0, 1]");
         for (double c : a)
           if (c < 0.0 || c > 1.0) throw UsageError("flag " + f + ": albedo must be in [0, 1], got '" + v + "'");
         options.albedo = {a[0], a[1], a[2]};
       }}};
  valued.insert(valued.end(), object_flags.begin(), object_flags.end());
  parseFlags(args, kRender, valued, lightSwitches(options.frame));
  giveBracketsToTheirFrames(args, options.frame);
  defaultToTheRecordingsFiles(options.frame);
  if (options.frame.frame_path.empty()) throw UsageError("render needs --frame FILE (the camera frame)");
  if (options.frame.camera_path.empty()) throw UsageError("render needs --calibration camera.yaml (the calibration of the camera that took it)");
  if (options.frame.rig_path.empty()) throw UsageError("render needs --rig rig.yaml");
  if (options.frame.out_dir.empty()) throw UsageError("render needs --out DIR (where composite.png and analysis.json go)");
  checkBracketCount(options.frame);
  if (!object_flag.empty() && !options.model_path.empty())
    throw UsageError("flag --object: not with --model (the model is the object)");
  if (!object_flag.empty()) options.object = object_flag;
  if (options.object != "model" && have_scale) throw UsageError("flag --scale: only with --model");
  if (options.object == "model" && options.radius_m != 0.0) throw UsageError("flag --radius: only for a sphere");
  if (options.object == "model" && have_size) throw UsageError("flag --size: only for --object box");
  if (options.object == "sphere" && options.radius_m == 0.0) throw UsageError("render needs --radius METRES for a sphere");
  if (options.object == "box" && !have_size) throw UsageError("render needs --size X,Y,Z (metres) for a box");
  if (options.object == "sphere" && have_size) throw UsageError("flag --size: only for --object box");
  return options;
}

CalibrateCameraOptions parseCalibrateCameraOptions(const std::vector<std::string>& args) {
  CalibrateCameraOptions options;
  parseFlags(args, kCalibrateCamera,
             {{"--images", "GLOB", "the views, e.g. 'captures/board_*.png' (quoted) (required)",
               [&](auto&, auto& v) { options.images = v; }},
              {"--board", "COLSxROWS", "inner corners of the chessboard, e.g. 9x6 (required)",
               [&](auto& f, auto& v) { parseBoard(f, v, options.board_cols, options.board_rows); }},
              {"--square", "METRES", "edge of one square, e.g. 0.025 (required)",
               [&](auto& f, auto& v) { options.square_m = parseSquare(f, v); }},
              {"-o,--out", "camera.yaml", "where the calibration goes (required)",
               [&](auto&, auto& v) { options.out_path = v; }}},
             {});
  if (options.images.empty()) throw UsageError("calibrate-camera needs --images GLOB (the chessboard views)");
  if (options.board_cols == 0) throw UsageError("calibrate-camera needs --board COLSxROWS (inner corners, e.g. 9x6)");
  if (options.square_m == 0.0) throw UsageError("calibrate-camera needs --square METRES (a square's edge, e.g. 0.025)");
  if (options.out_path.empty()) throw UsageError("calibrate-camera needs --out camera.yaml");
  return options;
}

PrintTagOptions parsePrintTagOptions(const std::vector<std::string>& args) {
  PrintTagOptions options;
  parseFlags(args, kPrintTag,
             {{"--rig", "rig.yaml", "the tag's family, id and tag_size (default: tag36h11 id 0, 100 mm, as board/rig.yaml)",
               [&](auto&, auto& v) { options.rig_path = v; }},
              {"-o,--out", "tag.png", "where the sheet goes (required)", [&](auto&, auto& v) { options.out_path = v; }},
              {"--dpi", "N", "the sheet's resolution, 72 to 1200 dots per inch (default 300)",
               [&](auto& f, auto& v) { options.dots_per_inch = static_cast<int>(parseInteger(f, v, 72, 1200)); }}},
             {});
  if (options.out_path.empty()) throw UsageError("print-tag needs --out tag.png");
  return options;
}

CamerasOptions parseCamerasOptions(const std::vector<std::string>& args) {
  CamerasOptions options;
  parseFlags(args, kCameras, {}, {});
  return options;
}

std::string usageText() {
  std::string text = "probelight: image-based lighting for an AR kiosk (mirror ball + AprilTag)\n\n"
                     "usage: probelight COMMAND [flags]\n\n"
                     "commands:\n";
  auto line = [&](const std::string& name, const std::string& summary) {
    std::string padded = "  " + name;
    padded.resize(std::max<std::size_t>(padded.size() + 2, 22), ' ');
    text += padded + summary.substr(0, summary.find('\n')) + "\n";
  };
  line(kRun.name, kRun.summary);
  line(kAnalyze.name, "one frame in: what the system sees (DIR/analysis.json and pictures)");
  line(kRender.name, "a virtual object put into one frame, lit and shadowed (DIR/composite.png)");
  line(kCalibrateCamera.name, "chessboard views in, camera.yaml out");
  line(kCameras.name, "the cameras libcamera finds, with their ids, formats and sizes");
  line(kPrintTag.name, "the rig's AprilTag as a PNG to print, to scale");
  line("help, -h, --help", "this overview");
  line("--version", "the version");
  text += R"(
probelight COMMAND --help (or -h) lists that command's flags.

exit status: 0 ok, 1 runtime failure, 2 bad flags or configuration
             (calibrate-camera: also no matching files or too few usable views),
             3 (analyze, render) the tag or the ball was not found: analysis.json says why.
)";
  return text;
}

}  // namespace probelight
