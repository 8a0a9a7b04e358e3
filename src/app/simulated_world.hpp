// The simulated world's settings between probelight.yaml's sim section, a
// recording's header (RecordedSimulation) and the simulator's SceneConfig:
// a live run records what it simulates, and a replay of that recording
// rebuilds the same world for its truth.
#pragma once

#include "app/app_settings.hpp"
#include "capture/frame_recording.hpp"
#include "sim/scene_config.hpp"

namespace probelight {

// probelight.yaml's sim section as a recording keeps it.
RecordedSimulation simulationOf(const SimConfig& sim);

// `scene` (its camera and rig already set: what the pipeline is told) given
// the world of `simulation`, the ball moved where sim.ball_offset puts it.
void applySimulation(const RecordedSimulation& simulation, sim::SceneConfig& scene);

}  // namespace probelight
