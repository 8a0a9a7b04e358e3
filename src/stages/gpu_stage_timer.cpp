#include "stages/gpu_stage_timer.hpp"

#include <GLES2/gl2.h>

namespace probelight {

GpuStageTimer::~GpuStageTimer() {
  if (finish_gpu_) glFinish();
}

}  // namespace probelight
