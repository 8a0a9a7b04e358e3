#include "sim/camera_ycbcr.hpp"

#include <algorithm>
#include <cmath>

namespace probelight::sim {
namespace {

std::uint8_t toCode(double value) { return static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L)); }

}  // namespace

void encodeYcbcr420Sycc(const ImageRGB8& rgb, std::uint8_t* y_plane, int y_stride, std::uint8_t* cb_plane,
                        std::uint8_t* cr_plane, int chroma_stride, int chroma_step) {
  // ITU-T T.871 (JFIF): Y = 0.299 R + 0.587 G + 0.114 B,
  // Cb = 128 + (B - Y) / 1.772, Cr = 128 + (R - Y) / 1.402, on 0-255 codes.
  const int width = rgb.width, height = rgb.height;
  for (int y = 0; y < height; ++y) {
    const std::uint8_t* row = rgb.row(y);
    for (int x = 0; x < width; ++x)
      y_plane[y * y_stride + x] = toCode(0.299 * row[3 * x] + 0.587 * row[3 * x + 1] + 0.114 * row[3 * x + 2]);
  }
  const int chroma_width = (width + 1) / 2, chroma_height = (height + 1) / 2;
  for (int cy = 0; cy < chroma_height; ++cy)
    for (int cx = 0; cx < chroma_width; ++cx) {
      double cb_sum = 0.0, cr_sum = 0.0;
      int count = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const int x = 2 * cx + dx, y = 2 * cy + dy;
          if (x >= width || y >= height) continue;
          const std::uint8_t* pixel = rgb.row(y) + 3 * x;
          const double luma = 0.299 * pixel[0] + 0.587 * pixel[1] + 0.114 * pixel[2];
          cb_sum += (pixel[2] - luma) / 1.772;
          cr_sum += (pixel[0] - luma) / 1.402;
          ++count;
        }
      cb_plane[cy * chroma_stride + cx * chroma_step] = toCode(128.0 + cb_sum / count);
      cr_plane[cy * chroma_stride + cx * chroma_step] = toCode(128.0 + cr_sum / count);
    }
}

void encodeYcbcr422Sycc(const ImageRGB8& rgb, std::uint8_t* plane, int stride) {
  const int width = rgb.width, height = rgb.height;
  auto luma = [](const std::uint8_t* pixel) { return 0.299 * pixel[0] + 0.587 * pixel[1] + 0.114 * pixel[2]; };
  for (int y = 0; y < height; ++y) {
    const std::uint8_t* row = rgb.row(y);
    std::uint8_t* out = plane + static_cast<std::size_t>(y) * static_cast<std::size_t>(stride);
    for (int pair = 0; 2 * pair < width; ++pair) {
      const int x0 = 2 * pair, x1 = std::min(x0 + 1, width - 1);
      double cb = 0.0, cr = 0.0;
      const int taps[3] = {std::max(x0 - 1, 0), x0, x1};
      const double weights[3] = {0.25, 0.5, 0.25};
      for (int t = 0; t < 3; ++t) {
        const std::uint8_t* pixel = row + 3 * taps[t];
        cb += weights[t] * (pixel[2] - luma(pixel)) / 1.772;
        cr += weights[t] * (pixel[0] - luma(pixel)) / 1.402;
      }
      out[4 * pair + 0] = toCode(luma(row + 3 * x0));
      out[4 * pair + 1] = toCode(128.0 + cb);
      out[4 * pair + 2] = toCode(luma(row + 3 * x1));
      out[4 * pair + 3] = toCode(128.0 + cr);
    }
  }
}

}  // namespace probelight::sim
