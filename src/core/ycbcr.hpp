// Y'CbCr as cameras deliver it (libcamera's YUV420 streams): which matrix
// (the luma weights Kr, Kb) and which code range. The decoding matrix is built
// from those two constants, so every standard comes out of one derivation
// instead of a table of magic numbers per standard.
#pragma once

#include <string>

namespace probelight {

enum class YcbcrMatrix { kRec601, kRec709, kRec2020 };

struct YcbcrEncoding {
  YcbcrMatrix matrix = YcbcrMatrix::kRec601;
  // Full range: Y' and C codes use 0-255 (JPEG, libcamera's sYCC). Limited:
  // Y' in 16-235 and C in 16-240 (video, Rec709 streams).
  bool full_range = true;

  bool operator==(const YcbcrEncoding& other) const {
    return matrix == other.matrix && full_range == other.full_range;
  }
  // "Rec601 full range"
  std::string describe() const;
};

// rgb = matrix * code + offset, with code = (Y', Cb, Cr) / 255 as a texture
// sampler returns them and rgb the non-linear R'G'B' in [0, 1] (before
// clamping). `matrix` is column-major (GLSL's mat3 layout).
struct YcbcrDecoding {
  float matrix[9];
  float offset[3];
};

YcbcrDecoding ycbcrDecoding(const YcbcrEncoding& encoding);

// The luma weights (Kr, Kb) of a matrix: Y' = Kr R' + (1 - Kr - Kb) G' + Kb B'.
void lumaWeights(YcbcrMatrix matrix, double& kr, double& kb);

}  // namespace probelight
