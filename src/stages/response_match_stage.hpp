// The camera's own response (issue 19): auto exposure and auto white
// balance move from frame to frame, and the object's light, measured in
// the frame the maps were last made from, is brought into each shown
// frame's units before it leaves through the camera's transfer: the
// per-channel ratio of the two frames' exposure x gain and colour gains
// (stages/frame_response.hpp) multiplies the object's linear colour
// (camera_response.glsl). When auto exposure darkens the frame, the object
// darkens with it, on the same frame, whether or not the maps are remade
// then (a ball out of view, a still camera's kept maps).
//
// Skips: off (camera_match.response), no_maps, unknown_response (the
// source's frames say neither exposure nor white balance).
#pragma once

#include <cstdint>
#include <string>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "stages/frame_response.hpp"
#include "stages/maps_stage.hpp"
#include "stages/pipeline_settings.hpp"
#include "stages/run_report.hpp"

namespace probelight {

class ResponseMatchStage {
 public:
  static constexpr const char* kStageName = "match_response";

  ResponseMatchStage(const CameraMatchConfig& config, RunReport& report) : config_(config), report_(report) {}

  // This frame's gain, from the maps' frame's response (1 when skipped).
  void run(const FrameBuffer& frame, const MapsStage& maps, std::uint64_t frame_number);
  // A frame the pipeline does not run on (a bracket's): the frame shown
  // again is the last one, with its gain.
  void skip(const std::string& reason);

  glm::dvec3 gain() const { return gain_rgb_; }

 private:
  void skipWithUnitGain(const std::string& reason);

  CameraMatchConfig config_;
  RunReport& report_;
  glm::dvec3 gain_rgb_{1.0};
  double lowest_stops_ = 0.0, highest_stops_ = 0.0;  // of the green gain, over the run
};

}  // namespace probelight
