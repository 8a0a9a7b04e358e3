#include "core/ycbcr.hpp"

namespace probelight {

std::string YcbcrEncoding::describe() const {
  const char* name = matrix == YcbcrMatrix::kRec601 ? "Rec601" : matrix == YcbcrMatrix::kRec709 ? "Rec709" : "Rec2020";
  return std::string(name) + (full_range ? " full range" : " limited range");
}

void lumaWeights(YcbcrMatrix matrix, double& kr, double& kb) {
  switch (matrix) {
    case YcbcrMatrix::kRec601: kr = 0.299; kb = 0.114; return;
    case YcbcrMatrix::kRec709: kr = 0.2126; kb = 0.0722; return;
    case YcbcrMatrix::kRec2020: kr = 0.2627; kb = 0.0593; return;
  }
  kr = 0.299;
  kb = 0.114;
}

YcbcrDecoding ycbcrDecoding(const YcbcrEncoding& encoding) {
  double kr = 0.0, kb = 0.0;
  lumaWeights(encoding.matrix, kr, kb);
  const double kg = 1.0 - kr - kb;
  // Normalised signals from codes c in [0, 1]: Y = (c_y - y0) * y_scale,
  // Cb/Cr = (c - 128/255) * c_scale, with Y in [0, 1] and Cb, Cr in [-0.5, 0.5].
  const double y_scale = encoding.full_range ? 1.0 : 255.0 / 219.0;
  const double y0 = encoding.full_range ? 0.0 : 16.0 / 255.0;
  const double c_scale = encoding.full_range ? 1.0 : 255.0 / 224.0;
  const double c0 = 128.0 / 255.0;
  // R = Y + 2(1-Kr) Cr;  B = Y + 2(1-Kb) Cb;  G = (Y - Kr R - Kb B) / Kg.
  const double r_cr = 2.0 * (1.0 - kr);
  const double b_cb = 2.0 * (1.0 - kb);
  const double g_cb = -kb * b_cb / kg;
  const double g_cr = -kr * r_cr / kg;
  // Rows (R, G, B) over columns (Y, Cb, Cr), before the scales.
  const double rows[3][3] = {{1.0, 0.0, r_cr}, {1.0, g_cb, g_cr}, {1.0, b_cb, 0.0}};
  const double scales[3] = {y_scale, c_scale, c_scale};
  const double zeros[3] = {y0, c0, c0};
  YcbcrDecoding decoding{};
  for (int row = 0; row < 3; ++row) {
    double offset = 0.0;
    for (int column = 0; column < 3; ++column) {
      const double m = rows[row][column] * scales[column];
      decoding.matrix[column * 3 + row] = static_cast<float>(m);
      offset -= m * zeros[column];
    }
    decoding.offset[row] = static_cast<float>(offset);
  }
  return decoding;
}

}  // namespace probelight
