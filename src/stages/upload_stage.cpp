#include "stages/upload_stage.hpp"

#include "stages/gpu_stage_timer.hpp"

namespace probelight {

Status UploadStage::init(const gles::Capabilities& capabilities) {
  std::string error;
  if (!texture_.init(capabilities, error)) return Status::runtimeFailure("GPU set-up failed: " + error);
  return Status::ok();
}

Status UploadStage::run(const FrameContext& frame) {
  GpuStageTimer timer(report_, kStageName, finish_gpu_);
  std::string error;
  if (!texture_.upload(frame.frame, error)) return Status::runtimeFailure(frame.frame.metadata.origin + ": " + error);
  return Status::ok();
}

void UploadStage::writeReport(nlohmann::json& camera_section) const {
  camera_section["frame_upload"] = passes::toString(texture_.lastPath());
  if (!texture_.dmabufImportProblem().empty()) camera_section["dmabuf_import_problem"] = texture_.dmabufImportProblem();
}

}  // namespace probelight
