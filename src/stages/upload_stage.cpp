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
  nlohmann::json by_path = nlohmann::json::object();
  for (passes::FrameUploadPath path :
       {passes::FrameUploadPath::kRgbUpload, passes::FrameUploadPath::kYuvUpload,
        passes::FrameUploadPath::kPackedRgbUpload, passes::FrameUploadPath::kDmabufImport})
    if (texture_.framesBy(path) > 0) by_path[passes::toString(path)] = texture_.framesBy(path);
  camera_section["frames_by_upload_path"] = by_path;
  camera_section["frames_in_dmabufs"] = texture_.framesInDmabufs();
  camera_section["dmabuf_import_fallbacks"] = texture_.dmabufImportFallbacks();
  if (const auto difference = texture_.importCheckMeanDifference())
    camera_section["dmabuf_import_vs_upload_mean_codes"] = *difference;
  if (const std::string reason = texture_.dmabufUploadReason(); !reason.empty())
    camera_section["dmabuf_import_problem"] = reason;
}

}  // namespace probelight
