// The upload stage: the camera frame onto the GPU (passes/camera_frame_texture:
// RGB as it is, YUV planes converted by a shader or imported as an EGLImage),
// where the maps and the composite read it.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "core/status.hpp"
#include "gles/capabilities.hpp"
#include "passes/camera_frame_texture.hpp"
#include "stages/frame_context.hpp"
#include "stages/run_report.hpp"

namespace probelight {

class UploadStage {
 public:
  static constexpr const char* kStageName = "upload";

  UploadStage(RunReport& report, bool finish_gpu) : report_(report), finish_gpu_(finish_gpu) {}
  Status init(const gles::Capabilities& capabilities);

  Status run(const FrameContext& frame);
  // A frame the pipeline does not run on (an exposure bracket's): counted.
  void skip(const std::string& reason) { report_.recordStageSkip(kStageName, reason); }

  // The last frame uploaded (empty before the first).
  const passes::CameraFrameTexture& texture() const { return texture_; }

  // The one line to say once when frames change path (a failed dmabuf
  // import and its cause); empty otherwise. Taking it clears it.
  std::string takeNotice() { return texture_.takeNotice(); }

  // report.json: camera.frame_upload (the path the last frame took),
  // frames_by_upload_path, frames_in_dmabufs, dmabuf_import_fallbacks,
  // dmabuf_import_vs_upload_mean_codes (the first imported frame against
  // the upload path) and dmabuf_import_problem (why frames in dmabufs take
  // the upload path).
  void writeReport(nlohmann::json& camera_section) const;

 private:
  RunReport& report_;
  bool finish_gpu_;
  passes::CameraFrameTexture texture_;
};

}  // namespace probelight
