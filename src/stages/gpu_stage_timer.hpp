// Times a GPU stage into the report. With finish_gpu (probelight.yaml
// gpu_finish, on by default) it waits for the GPU (glFinish) before the
// time is taken, so that the time is the GPU's work and not just the
// queuing of it; off, the driver may pipeline stages and the times mean less.
#pragma once

#include <string>
#include <utility>

#include "stages/run_report.hpp"

namespace probelight {

class GpuStageTimer {
 public:
  GpuStageTimer(RunReport& report, std::string stage, bool finish_gpu)
      : finish_gpu_(finish_gpu), timer_(report, std::move(stage)) {}
  ~GpuStageTimer();  // glFinish, then timer_ records
  GpuStageTimer(const GpuStageTimer&) = delete;
  GpuStageTimer& operator=(const GpuStageTimer&) = delete;

 private:
  bool finish_gpu_;
  StageTimer timer_;
};

}  // namespace probelight
