#include "capture/frame_recording.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include <nlohmann/json.hpp>

#include "core/file_bytes.hpp"

namespace probelight {

namespace fs = std::filesystem;

namespace {

using Json = nlohmann::json;

constexpr PixelLayout kAllLayouts[] = {PixelLayout::kRgb8,   PixelLayout::kI420,   PixelLayout::kNv12,
                                       PixelLayout::kYuyv,   PixelLayout::kRgb888, PixelLayout::kBgr888,
                                       PixelLayout::kXrgb8888};
// A frame's metadata is a few hundred bytes; a .json of megabytes is not one.
constexpr std::uint64_t kMaxFrameJsonBytes = 64 * 1024;
// Cameras pad rows to 32, 64 or at most a page; a stride this much beyond a
// row's pixels is a damaged field, not a camera's.
constexpr int kMaxStridePaddingBytes = 4096;
constexpr double kMaxExposureUs = 1e8;  // 100 s: longer than any sensor's
constexpr double kMaxAnalogueGain = 1024.0;
constexpr double kMaxColourGain = 32.0;  // libcamera's ColourGains range

const char* matrixName(YcbcrMatrix matrix) {
  return matrix == YcbcrMatrix::kRec601 ? "Rec601" : matrix == YcbcrMatrix::kRec709 ? "Rec709" : "Rec2020";
}

// Thrown while reading a file's fields: the field and what is wrong with it.
struct FieldError : std::runtime_error {
  FieldError(const std::string& field, const std::string& what) : std::runtime_error("field '" + field + "': " + what) {}
};

// `prefix` names the object the field is in ("planes[1]."), for the message.
// A view, not a const std::string&: these return references into `object`,
// and a defaulted string argument is a temporary that GCC 14's
// -Wdangling-reference takes for what the reference might point into.
const Json& member(const Json& object, const char* key, std::string_view prefix = {}) {
  const auto found = object.find(key);
  if (found == object.end()) throw FieldError(std::string(prefix) + key, "missing");
  return *found;
}

double number(const Json& object, const char* key, double low, double high, const std::string& prefix = "") {
  const std::string field = prefix + key;
  const Json& value = member(object, key, prefix);
  if (!value.is_number()) throw FieldError(field, "not a number");
  const double x = value.get<double>();
  if (!std::isfinite(x) || x < low || x > high)
    throw FieldError(field, value.dump() + " is outside [" + Json(low).dump() + ", " + Json(high).dump() + "]");
  return x;
}

long long integer(const Json& object, const char* key, long long low, long long high,
                  const std::string& prefix = "") {
  const std::string field = prefix + key;
  const Json& value = member(object, key, prefix);
  if (!value.is_number_integer()) throw FieldError(field, "not a whole number");
  // Read as the widest signed type first: a huge unsigned value is refused, not wrapped.
  if (value.is_number_unsigned() && value.get<std::uint64_t>() > static_cast<std::uint64_t>(high))
    throw FieldError(field, value.dump() + " is outside [" + std::to_string(low) + ", " + std::to_string(high) + "]");
  const long long x = value.get<long long>();
  if (x < low || x > high)
    throw FieldError(field, value.dump() + " is outside [" + std::to_string(low) + ", " + std::to_string(high) + "]");
  return x;
}

const std::string& text(const Json& object, const char* key, std::string_view prefix = {}) {
  const std::string field = std::string(prefix) + key;
  const Json& value = member(object, key, prefix);
  if (!value.is_string()) throw FieldError(field, "not a string");
  return value.get_ref<const std::string&>();
}

// `count` numbers in [low, high] in the list `key` of `object`.
std::vector<double> numberList(const Json& object, const char* key, std::size_t count, double low, double high,
                               const std::string& prefix) {
  const std::string field = prefix + key;
  const Json& value = member(object, key, prefix);
  if (!value.is_array() || value.size() != count)
    throw FieldError(field, "not a list of " + std::to_string(count) + " numbers");
  std::vector<double> out;
  for (const Json& item : value) {
    if (!item.is_number()) throw FieldError(field, "holds " + item.dump() + ", not a number");
    const double x = item.get<double>();
    if (!std::isfinite(x) || x < low || x > high)
      throw FieldError(field, item.dump() + " is outside [" + Json(low).dump() + ", " + Json(high).dump() + "]");
    out.push_back(x);
  }
  return out;
}

bool boolean(const Json& object, const char* key, const std::string& prefix = "") {
  const Json& value = member(object, key, prefix);
  if (!value.is_boolean()) throw FieldError(prefix + key, "not true or false");
  return value.get<bool>();
}

// Far beyond any frame or scene: a damaged number, not a simulator's.
constexpr double kMaxTruthPx = 1e6;
constexpr double kMaxTruthMetres = 1e3;

Json truthJson(const FrameTruth& truth) {
  Json rotation = Json::array();
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) rotation.push_back(truth.pose.R_cam_from_world[col][row]);
  const glm::dvec3& t = truth.pose.t_cam_from_world;
  return {{"R_cam_from_world", rotation},  // row by row
          {"t_cam_from_world_m", {t.x, t.y, t.z}},
          {"probe_center_px", {truth.probe_center_px.x, truth.probe_center_px.y}},
          {"probe_radius_px", truth.probe_radius_px},
          {"exposure", truth.exposure},
          {"tag_fully_visible", truth.tag_fully_visible},
          {"probe_fully_visible", truth.probe_fully_visible}};
}

FrameTruth readTruth(const Json& json) {
  if (!json.is_object()) throw FieldError("truth", "not an object");
  const std::string prefix = "truth.";
  FrameTruth truth;
  const std::vector<double> rotation = numberList(json, "R_cam_from_world", 9, -1.0 - 1e-9, 1.0 + 1e-9, prefix);
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) truth.pose.R_cam_from_world[col][row] = rotation[3 * row + col];
  // A rotation: its columns orthonormal within what 17 written digits keep.
  const glm::dmat3 product = glm::transpose(truth.pose.R_cam_from_world) * truth.pose.R_cam_from_world;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (std::abs(product[i][j] - (i == j ? 1.0 : 0.0)) > 1e-9)
        throw FieldError("truth.R_cam_from_world", "not a rotation (R^T R is not the identity)");
  const std::vector<double> t = numberList(json, "t_cam_from_world_m", 3, -kMaxTruthMetres, kMaxTruthMetres, prefix);
  truth.pose.t_cam_from_world = glm::dvec3(t[0], t[1], t[2]);
  const std::vector<double> center = numberList(json, "probe_center_px", 2, -kMaxTruthPx, kMaxTruthPx, prefix);
  truth.probe_center_px = glm::dvec2(center[0], center[1]);
  truth.probe_radius_px = number(json, "probe_radius_px", 0.0, kMaxTruthPx, prefix);
  truth.exposure = number(json, "exposure", 0.0, kMaxTruthPx, prefix);
  truth.tag_fully_visible = boolean(json, "tag_fully_visible", prefix);
  truth.probe_fully_visible = boolean(json, "probe_fully_visible", prefix);
  return truth;
}

Json simulationJson(const RecordedSimulation& simulation) {
  return {{"environment", simulation.environment},
          {"camera_path", simulation.camera_path},
          {"noise_sigma_code", simulation.noise_sigma_code},
          {"lens_blur_sigma_px", simulation.lens_blur_sigma_px},
          {"seed", simulation.seed},
          {"sun_azimuth_rate_deg_per_frame", simulation.sun_azimuth_rate_deg_per_frame},
          {"environment_rotation_deg", simulation.environment_rotation_deg},
          {"lamp_on_frame", simulation.lamp_on_frame},
          {"lamp_off_frame", simulation.lamp_off_frame},
          {"ball_offset_m", {simulation.ball_offset_m[0], simulation.ball_offset_m[1], simulation.ball_offset_m[2]}}};
}

// The ranges are wide (the simulator checks its scene itself when the
// replay builds it); what is refused here is a damaged number.
RecordedSimulation readSimulation(const Json& json) {
  if (!json.is_object()) throw FieldError("simulation", "not an object");
  const std::string prefix = "simulation.";
  constexpr double kFrames = 1e15;
  RecordedSimulation simulation;
  simulation.environment = text(json, "environment", prefix);
  simulation.camera_path = text(json, "camera_path", prefix);
  simulation.noise_sigma_code = number(json, "noise_sigma_code", 0.0, 255.0, prefix);
  simulation.lens_blur_sigma_px = number(json, "lens_blur_sigma_px", 0.0, 1000.0, prefix);
  simulation.seed = static_cast<std::uint64_t>(integer(json, "seed", 0, std::numeric_limits<long long>::max(), prefix));
  simulation.sun_azimuth_rate_deg_per_frame = number(json, "sun_azimuth_rate_deg_per_frame", -360.0, 360.0, prefix);
  simulation.environment_rotation_deg = number(json, "environment_rotation_deg", -1e6, 1e6, prefix);
  simulation.lamp_on_frame = integer(json, "lamp_on_frame", -1, static_cast<long long>(kFrames), prefix);
  simulation.lamp_off_frame = integer(json, "lamp_off_frame", -1, static_cast<long long>(kFrames), prefix);
  const std::vector<double> offset = numberList(json, "ball_offset_m", 3, -kMaxTruthMetres, kMaxTruthMetres, prefix);
  for (int i = 0; i < 3; ++i) simulation.ball_offset_m[i] = offset[static_cast<std::size_t>(i)];
  return simulation;
}

// Parses a small JSON file; a syntax error or a file that is not an object
// throws FieldError-like runtime_error naming no field.
Json readJsonObject(const std::string& path, std::uint64_t max_bytes) {
  std::vector<std::uint8_t> bytes;
  std::string why;
  if (!readWholeFile(path, max_bytes, bytes, why)) throw std::runtime_error(why);
  // Depth-limited: a recording's files are two levels deep; a file nested
  // thousands deep is damage (and would only exhaust the stack).
  Json root = Json::parse(
      bytes.begin(), bytes.end(),
      [](int depth, Json::parse_event_t, Json&) {
        if (depth > 8) throw std::runtime_error("nested deeper than a recording's files are");
        return true;
      },
      false);
  if (root.is_discarded()) throw std::runtime_error("not valid JSON");
  if (!root.is_object()) throw std::runtime_error("not a JSON object");
  return root;
}

// `error`: the path and why ("No space left on device").
bool writeFile(const fs::path& path, const void* data, std::size_t size, std::string& error) {
  errno = 0;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (out) out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (out) out.close();
  if (!out) {
    error = path.string() + (errno != 0 ? std::string(": ") + std::strerror(errno) : std::string());
    return false;
  }
  return true;
}

// Written under a temporary name and renamed into place, so that a reader
// (or a recording cut short) never sees half of it.
bool writeFileWhole(const fs::path& path, const std::string& content, std::string& error) {
  const fs::path partial = path.string() + ".partial";
  if (!writeFile(partial, content.data(), content.size(), error)) return false;
  std::error_code ec;
  fs::rename(partial, path, ec);
  if (ec) {
    error = path.string() + ": " + ec.message();
    return false;
  }
  return true;
}

}  // namespace

int planeRows(PixelLayout layout, int plane, int height_px) {
  return plane > 0 && (layout == PixelLayout::kI420 || layout == PixelLayout::kNv12) ? (height_px + 1) / 2 : height_px;
}

int planeRowBytes(PixelLayout layout, int plane, int width_px) {
  const int chroma_width = (width_px + 1) / 2;
  switch (layout) {
    case PixelLayout::kRgb8: return 3 * width_px;
    case PixelLayout::kI420: return plane == 0 ? width_px : chroma_width;
    case PixelLayout::kNv12: return plane == 0 ? width_px : 2 * chroma_width;
    case PixelLayout::kYuyv: return 4 * chroma_width;  // whole pairs
    default: return packedBytesPerPixel(layout) * width_px;
  }
}

std::string recordedFrameStem(std::uint64_t index) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%06llu", static_cast<unsigned long long>(index));
  return name;
}

RecordedFrame copyFrameForRecording(const FrameBuffer& frame) {
  RecordedFrame out;
  out.layout = frame.layout;
  out.width_px = frame.width_px;
  out.height_px = frame.height_px;
  out.encoding = frame.planes.encoding;
  out.metadata = frame.metadata;
  out.plane_count = planeCount(frame.layout);
  if (frame.layout == PixelLayout::kRgb8) {
    out.stride_bytes[0] = 3 * frame.width_px;
    out.plane_bytes[0] = frame.rgb.pixels.size();
    out.bytes = frame.rgb.pixels;
    return out;
  }
  std::size_t total = 0;
  for (int p = 0; p < out.plane_count; ++p) {
    out.stride_bytes[p] = frame.planes.stride_bytes[p];
    out.plane_bytes[p] = static_cast<std::size_t>(frame.planes.stride_bytes[p]) *
                         static_cast<std::size_t>(planeRows(frame.layout, p, frame.height_px));
    total += out.plane_bytes[p];
  }
  out.bytes.resize(total);
  std::size_t at = 0;
  for (int p = 0; p < out.plane_count; ++p) {
    // The last row of a camera's plane may stop at its pixels (no padding
    // after it in the buffer): copy that row's pixels only, padding zeroed.
    const int rows = planeRows(frame.layout, p, frame.height_px);
    const std::size_t stride = static_cast<std::size_t>(out.stride_bytes[p]);
    if (rows > 1) std::memcpy(out.bytes.data() + at, frame.planes.data[p], stride * static_cast<std::size_t>(rows - 1));
    std::memcpy(out.bytes.data() + at + stride * static_cast<std::size_t>(rows - 1),
                frame.planes.data[p] + stride * static_cast<std::size_t>(rows - 1),
                static_cast<std::size_t>(planeRowBytes(frame.layout, p, frame.width_px)));
    at += out.plane_bytes[p];
  }
  return out;
}

bool writeRecordingHeader(const std::string& dir, const RecordingHeader& header, std::string& error) {
  Json json = {{"format", "probelight recording"},
               {"version", kRecordingVersion},
               {"source", header.source},
               {"stream", header.stream},
               {"exposure_control", header.exposure_control},
               {"camera", "camera.yaml"},
               {"rig", "rig.yaml"}};
  if (header.shortest_exposure_us) json["shortest_exposure_us"] = *header.shortest_exposure_us;
  if (header.simulation) json["simulation"] = simulationJson(*header.simulation);
  return writeFileWhole(fs::path(dir) / kRecordingHeaderFile, json.dump(2) + "\n", error);
}

bool writeRecordedFrame(const std::string& dir, const std::string& stem, const RecordedFrame& frame,
                        std::string& error) {
  const fs::path raw = fs::path(dir) / (stem + ".raw");
  if (!writeFile(raw, frame.bytes.data(), frame.bytes.size(), error)) return false;
  Json planes = Json::array();
  for (int p = 0; p < frame.plane_count; ++p)
    planes.push_back({{"stride_bytes", frame.stride_bytes[p]}, {"bytes", frame.plane_bytes[p]}});
  Json json = {{"raw", stem + ".raw"},
               {"format", layoutName(frame.layout)},
               {"width_px", frame.width_px},
               {"height_px", frame.height_px},
               {"planes", planes},
               {"sequence", frame.metadata.sequence},
               {"timestamp_ns", frame.metadata.timestamp_ns},
               {"exposure_us", frame.metadata.exposure_us},
               {"analogue_gain", frame.metadata.analogue_gain},
               {"red_gain", frame.metadata.red_gain},
               {"blue_gain", frame.metadata.blue_gain},
               {"origin", frame.metadata.origin}};
  if (frame.metadata.lens_position_dioptres) json["lens_position_dioptres"] = *frame.metadata.lens_position_dioptres;
  if (frame.metadata.truth) json["truth"] = truthJson(*frame.metadata.truth);
  if (isYuv(frame.layout))
    json["ycbcr"] = {{"matrix", matrixName(frame.encoding.matrix)}, {"range", frame.encoding.full_range ? "full" : "limited"}};
  return writeFileWhole(fs::path(dir) / (stem + ".json"), json.dump(2) + "\n", error);
}

Status readRecordingHeader(const std::string& dir, RecordingHeader& header) {
  const std::string path = (fs::path(dir) / kRecordingHeaderFile).string();
  try {
    const Json json = readJsonObject(path, kMaxFrameJsonBytes);
    if (text(json, "format") != "probelight recording") throw FieldError("format", "not \"probelight recording\"");
    const long long version = integer(json, "version", 0, std::numeric_limits<int>::max());
    if (version != kRecordingVersion)
      throw FieldError("version", std::to_string(version) + " is not " + std::to_string(kRecordingVersion) +
                                      ", the version this probelight reads");
    RecordingHeader read;
    read.source = text(json, "source");
    read.stream = text(json, "stream");
    const Json& control = member(json, "exposure_control");
    if (!control.is_boolean()) throw FieldError("exposure_control", "not true or false");
    read.exposure_control = control.get<bool>();
    if (json.contains("shortest_exposure_us"))
      read.shortest_exposure_us = number(json, "shortest_exposure_us", 0.0, kMaxExposureUs);
    if (json.contains("simulation")) read.simulation = readSimulation(json["simulation"]);
    header = std::move(read);
  } catch (const std::exception& error) {
    return Status::badInput(path + ": " + error.what());
  }
  return Status::ok();
}

std::vector<std::string> listRecordedFrames(const std::string& dir) {
  std::vector<std::string> frames;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() == 17 && name.compare(0, 6, "frame_") == 0 && name.compare(12, 5, ".json") == 0 &&
        std::all_of(name.begin() + 6, name.begin() + 12, [](char c) { return c >= '0' && c <= '9'; }))
      frames.push_back(it->path().string());
  }
  std::sort(frames.begin(), frames.end());
  return frames;
}

bool isRecordedFramePath(const std::string& path) {
  const std::string extension = fs::path(path).extension().string();
  return extension == ".json" || extension == ".raw";
}

Status readRecordedFrame(const std::string& path, FrameBuffer& frame) {
  fs::path json_path = path;
  if (json_path.extension() == ".raw") json_path.replace_extension(".json");
  const fs::path dir = json_path.parent_path();
  std::string raw_name;
  try {
    const Json json = readJsonObject(json_path.string(), kMaxFrameJsonBytes);
    const std::string& format = text(json, "format");
    std::optional<PixelLayout> layout;
    for (PixelLayout candidate : kAllLayouts)
      if (format == layoutName(candidate)) layout = candidate;
    if (!layout) throw FieldError("format", "\"" + format + "\" is not one of RGB, YUV420, NV12, YUYV, RGB888, BGR888, XRGB8888");
    const int width = static_cast<int>(integer(json, "width_px", 1, kMaxImageSidePx));
    const int height = static_cast<int>(integer(json, "height_px", 1, kMaxImageSidePx));
    YcbcrEncoding encoding;
    if (isYuv(*layout)) {
      const Json& ycbcr = member(json, "ycbcr");
      if (!ycbcr.is_object()) throw FieldError("ycbcr", "not an object");
      const std::string& matrix = text(ycbcr, "matrix", "ycbcr.");
      if (matrix == "Rec601") encoding.matrix = YcbcrMatrix::kRec601;
      else if (matrix == "Rec709") encoding.matrix = YcbcrMatrix::kRec709;
      else if (matrix == "Rec2020") encoding.matrix = YcbcrMatrix::kRec2020;
      else throw FieldError("ycbcr.matrix", "\"" + matrix + "\" is not Rec601, Rec709 or Rec2020");
      const std::string& range = text(ycbcr, "range", "ycbcr.");
      if (range != "full" && range != "limited") throw FieldError("ycbcr.range", "\"" + range + "\" is not full or limited");
      encoding.full_range = range == "full";
    }
    const Json& planes = member(json, "planes");
    const int plane_count = planeCount(*layout);
    if (!planes.is_array() || planes.size() != static_cast<std::size_t>(plane_count))
      throw FieldError("planes", std::string("not a list of ") + std::to_string(plane_count) + " plane(s), as " +
                                     format + " has");
    int strides[3] = {0, 0, 0};
    std::size_t offsets[3] = {0, 0, 0};
    std::size_t total = 0;
    for (int p = 0; p < plane_count; ++p) {
      const std::string field = "planes[" + std::to_string(p) + "]";
      const Json& plane = planes[static_cast<std::size_t>(p)];
      if (!plane.is_object()) throw FieldError(field, "not an object");
      const int row_bytes = planeRowBytes(*layout, p, width);
      const int max_stride = *layout == PixelLayout::kRgb8 ? row_bytes : row_bytes + kMaxStridePaddingBytes;
      strides[p] = static_cast<int>(integer(plane, "stride_bytes", row_bytes, max_stride, field + "."));
      const std::size_t expected = static_cast<std::size_t>(strides[p]) *
                                   static_cast<std::size_t>(planeRows(*layout, p, height));
      const long long bytes = integer(plane, "bytes", 0, std::numeric_limits<long long>::max(), field + ".");
      if (static_cast<std::size_t>(bytes) != expected)
        throw FieldError(field + ".bytes", std::to_string(bytes) + " is not stride_bytes x rows = " + std::to_string(expected));
      offsets[p] = total;
      total += expected;
    }
    const long long sequence = integer(json, "sequence", 0, std::numeric_limits<long long>::max());
    const long long timestamp_ns = integer(json, "timestamp_ns", 0, std::numeric_limits<long long>::max());
    const double exposure_us = number(json, "exposure_us", 0.0, kMaxExposureUs);
    const double analogue_gain = number(json, "analogue_gain", 0.0, kMaxAnalogueGain);
    // The white balance's gains (recordings before them say none: 0, unknown).
    const double red_gain = json.contains("red_gain") ? number(json, "red_gain", 0.0, kMaxColourGain) : 0.0;
    const double blue_gain = json.contains("blue_gain") ? number(json, "blue_gain", 0.0, kMaxColourGain) : 0.0;
    // Where the lens was; absent in recordings made before it was kept and
    // of cameras without a lens control.
    std::optional<double> lens_position_dioptres;
    if (json.contains("lens_position_dioptres"))
      lens_position_dioptres = number(json, "lens_position_dioptres", 0.0, kMaxLensPositionDioptres);
    std::optional<FrameTruth> truth;
    if (json.contains("truth")) truth = readTruth(json["truth"]);
    raw_name = text(json, "raw");
    if (raw_name.empty() || raw_name.find('/') != std::string::npos || raw_name == "." || raw_name == "..")
      throw FieldError("raw", "not a file name in the recording's folder");

    std::vector<std::uint8_t> bytes;
    std::string why;
    const std::string raw_path = (dir / raw_name).string();
    if (!readWholeFile(raw_path, total, bytes, why) || bytes.size() != total)
      return Status::badInput(raw_path + ": " + (why.empty() ? std::to_string(bytes.size()) + " bytes" : why) +
                              ", but " + json_path.string() + " says its planes hold " + std::to_string(total));

    frame.metadata = FrameMetadata{};
    frame.metadata.sequence = static_cast<std::uint64_t>(sequence);
    frame.metadata.timestamp_ns = timestamp_ns;
    frame.metadata.exposure_us = exposure_us;
    frame.metadata.analogue_gain = analogue_gain;
    frame.metadata.red_gain = red_gain;
    frame.metadata.blue_gain = blue_gain;
    frame.metadata.lens_position_dioptres = lens_position_dioptres;
    frame.metadata.origin = json_path.string();
    frame.metadata.truth = truth;
    frame.width_px = width;
    frame.height_px = height;
    frame.layout = *layout;
    if (*layout == PixelLayout::kRgb8) {
      frame.rgb.width = width;
      frame.rgb.height = height;
      frame.rgb.pixels = std::move(bytes);
      frame.plane_storage.clear();
      frame.planes = FramePlanes{};
      frame.finishRgb();
      return Status::ok();
    }
    frame.rgb = ImageRGB8{};
    frame.luma_storage.clear();
    frame.plane_storage = std::move(bytes);
    frame.planes = FramePlanes{};
    frame.planes.encoding = encoding;
    for (int p = 0; p < plane_count; ++p) {
      frame.planes.data[p] = frame.plane_storage.data() + offsets[p];
      frame.planes.stride_bytes[p] = strides[p];
    }
    if (isPacked(*layout)) frame.finishPacked();
  } catch (const std::exception& error) {
    return Status::badInput(json_path.string() + ": " + error.what());
  }
  return Status::ok();
}

}  // namespace probelight
