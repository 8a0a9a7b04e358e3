// The simulated camera's ISP output format: what libcamera's YUV420 stream
// gives on the board with the sYCC colour space (JPEG's full-range Rec601
// Y'CbCr), chroma averaged over each 2x2 block (centre-sited). Written from
// the standard's forward equations on its own, so a mistake in the
// pipeline's decoder (core/ycbcr) cannot cancel against it.
#pragma once

#include <cstdint>

#include "core/types.hpp"

namespace probelight::sim {

// Chroma planes of ceil(w/2) x ceil(h/2) samples; strides in bytes.
// `chroma_step` is the byte step between samples of one chroma row: 1 for
// planar I420 (YUV420), 2 for NV12, whose Cb and Cr interleave in one plane
// (cr_plane = cb_plane + 1).
void encodeYcbcr420Sycc(const ImageRGB8& rgb, std::uint8_t* y_plane, int y_stride, std::uint8_t* cb_plane,
                        std::uint8_t* cr_plane, int chroma_stride, int chroma_step);

// YUYV (4:2:2, one plane of Y'0 Cb Y'1 Cr per pixel pair), as a USB
// webcam gives it: chroma sample k sits on pixel 2k (co-sited, BT.601) and
// is filtered [1/4, 1/2, 1/4] over pixels 2k-1, 2k, 2k+1 (edges repeated).
// An odd width's last pair repeats its pixel's Y'.
void encodeYcbcr422Sycc(const ImageRGB8& rgb, std::uint8_t* plane, int stride);

}  // namespace probelight::sim
