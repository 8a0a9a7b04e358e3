#include "ibl/probe_to_cube.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <thread>
#include <vector>

#include "ibl/color_transfer.hpp"

namespace probelight::ibl {

namespace {

// Bilinear fetch of the 8-bit encoded values, in [0, 1], at a pixel position
// in OpenCV's convention (pixel (u, v)'s centre at integer (u, v), as
// projectToPixel and calibration use), edges clamped: what a GL_LINEAR,
// CLAMP_TO_EDGE texture returns at texcoord = (pixel + 0.5) / size.
glm::dvec3 sampleEncodedBilinear(const ImageRGB8& image, const glm::dvec2& pixel) {
  const double u = pixel.x;
  const double v = pixel.y;
  const double u_floor = std::floor(u);
  const double v_floor = std::floor(v);
  const double fu = u - u_floor;
  const double fv = v - v_floor;
  const int x0 = std::clamp(static_cast<int>(u_floor), 0, image.width - 1);
  const int x1 = std::clamp(static_cast<int>(u_floor) + 1, 0, image.width - 1);
  const int y0 = std::clamp(static_cast<int>(v_floor), 0, image.height - 1);
  const int y1 = std::clamp(static_cast<int>(v_floor) + 1, 0, image.height - 1);
  auto fetch = [&image](int x, int y) {
    const std::uint8_t* p = image.row(y) + static_cast<size_t>(x) * 3u;
    return glm::dvec3(p[0], p[1], p[2]) / 255.0;
  };
  const glm::dvec3 top = glm::mix(fetch(x0, y0), fetch(x1, y0), fu);
  const glm::dvec3 bottom = glm::mix(fetch(x0, y1), fetch(x1, y1), fu);
  return glm::mix(top, bottom, fv);
}

// Same, for a linear float image.
glm::dvec3 sampleLinearBilinear(const ImageRGBF& image, const glm::dvec2& pixel) {
  const double u_floor = std::floor(pixel.x);
  const double v_floor = std::floor(pixel.y);
  const double fu = pixel.x - u_floor;
  const double fv = pixel.y - v_floor;
  const int x0 = std::clamp(static_cast<int>(u_floor), 0, image.width - 1);
  const int x1 = std::clamp(static_cast<int>(u_floor) + 1, 0, image.width - 1);
  const int y0 = std::clamp(static_cast<int>(v_floor), 0, image.height - 1);
  const int y1 = std::clamp(static_cast<int>(v_floor) + 1, 0, image.height - 1);
  auto fetch = [&image](int x, int y) { return glm::dvec3(image.at(x, y)); };
  const glm::dvec3 top = glm::mix(fetch(x0, y0), fetch(x1, y0), fu);
  const glm::dvec3 bottom = glm::mix(fetch(x0, y1), fetch(x1, y1), fu);
  return glm::mix(top, bottom, fv);
}

// Every texel whose direction the ball shows gets sampleLinear(pixel) /
// reflectance; the blind spot stays 0. With samples_per_axis k > 1 a texel
// takes as many samples a side as the pixels it spans (its corners'
// distance in the image, rounded up, at most k): near the ball's middle a
// texel is a fraction of a pixel and its centre says all (the bilinear
// fetch already mixes the pixels around it), near the rim it spans several
// and each needs a sample. Faces are shared among the machine's cores.
// `sample(direction_w, lower_bound)` gives the linear value seen in that
// direction (nullopt: not seen) and may set lower_bound; `lower_bounds`,
// when given, gets 1 for each texel with such a sample.
template <typename SampleDirection>
CubeMapRGB sampleCube(const MirrorBallView& view, const ProbeToCubeParams& params, SampleDirection sample,
                      std::vector<std::uint8_t>* lower_bounds = nullptr) {
  CubeMapRGB cube(params.face_size);
  if (lower_bounds) lower_bounds->assign(static_cast<std::size_t>(kCubeFaceCount) * params.face_size * params.face_size, 0);
  const double inverse_reflectance = params.probe_reflectance > 0.0 ? 1.0 / params.probe_reflectance : 0.0;
  const int k_max = std::max(1, params.samples_per_axis);
  const int n = params.face_size;
  const double size = n;
  auto doFace = [&](int face) {
    // Texel corners in the image (k_max > 1 only); nullopt: the blind spot.
    std::vector<std::optional<glm::dvec2>> corners;
    if (k_max > 1) {
      corners.resize(static_cast<std::size_t>(n + 1) * (n + 1));
      for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x)
          corners[static_cast<std::size_t>(y) * (n + 1) + x] = reflectedDirectionToPixel(
              view, cubeCoordToDirection({face, x / size, y / size}), params.normal_iterations);
    }
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        int k = 1;
        if (k_max > 1) {
          const auto& c00 = corners[static_cast<std::size_t>(y) * (n + 1) + x];
          const auto& c10 = corners[static_cast<std::size_t>(y) * (n + 1) + x + 1];
          const auto& c01 = corners[static_cast<std::size_t>(y + 1) * (n + 1) + x];
          const auto& c11 = corners[static_cast<std::size_t>(y + 1) * (n + 1) + x + 1];
          if (!c00 || !c10 || !c01 || !c11) {
            k = k_max;  // at the blind spot's edge: as many as allowed
          } else {
            const double span_px = std::max({glm::length(*c10 - *c00), glm::length(*c01 - *c00),
                                             glm::length(*c11 - *c10), glm::length(*c11 - *c01)});
            k = std::clamp(static_cast<int>(std::ceil(span_px)), 1, k_max);
          }
        }
        glm::dvec3 sum(0.0);
        int seen = 0;
        for (int j = 0; j < k; ++j)
          for (int i = 0; i < k; ++i) {
            const glm::dvec3 direction_w =
                k == 1 ? cubeTexelCenterDirection(face, x, y, n)
                       : cubeCoordToDirection({face, (x + (i + 0.5) / k) / size, (y + (j + 0.5) / k) / size});
            bool lower_bound = false;
            const std::optional<glm::dvec3> value = sample(direction_w, lower_bound);
            if (!value) continue;  // the blind spot
            sum += *value;
            ++seen;
            if (lower_bound && lower_bounds)
              (*lower_bounds)[static_cast<std::size_t>(face) * n * n + static_cast<std::size_t>(y) * n + x] = 1;
          }
        if (seen > 0) cube.texel(face, x, y) = glm::vec3(sum / static_cast<double>(seen) * inverse_reflectance);
      }
  };
  const int threads = std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, kCubeFaceCount);
  if (threads == 1 || n < 16) {
    for (int face = 0; face < kCubeFaceCount; ++face) doFace(face);
    return cube;
  }
  // Each face is written by one thread only.
  std::vector<std::thread> workers;
  for (int t = 0; t < threads; ++t)
    workers.emplace_back([&, t] {
      for (int face = t; face < kCubeFaceCount; face += threads) doFace(face);
    });
  for (std::thread& worker : workers) worker.join();
  return cube;
}

}  // namespace

CubeMapRGB bracketToCubeMap(const std::vector<BracketView>& frames, const HdrMergeSettings& merge,
                            const ProbeToCubeParams& params, std::vector<std::uint8_t>* still_clipped) {
  if (frames.empty() || !frames.front().image || frames.front().image->empty()) return CubeMapRGB(params.face_size);
  std::array<double, 256> decoded{};
  for (int code = 0; code < 256; ++code) decoded[static_cast<std::size_t>(code)] = decodeCameraValue(merge.camera_transfer, code / 255.0);
  // Per frame only its exposure ratio: the pixels a sample reads are
  // decoded and weighted as it reads them (a few per direction), not the
  // whole frame.
  std::vector<double> ratios;
  std::size_t shortest = 0, longest = 0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    ratios.push_back(std::exp2(frames[f].ev));
    if (frames[f].ev < frames[shortest].ev) shortest = f;
    if (frames[f].ev > frames[longest].ev) longest = f;
  }
  auto codeAt = [&](std::size_t f, int index, int c) {
    return static_cast<int>(frames[f].image->pixels[3 * static_cast<std::size_t>(index) + static_cast<std::size_t>(c)]);
  };
  auto linearAt = [&](std::size_t f, int index, int c) { return decoded[static_cast<std::size_t>(codeAt(f, index, c))] / ratios[f]; };
  auto hatAt = [&](std::size_t f, int index, int c) {
    const int code = codeAt(f, index, c);
    const int hat = (code <= merge.dark_code || code >= merge.clip_code) ? 0 : std::min(code - merge.dark_code, merge.clip_code - code);
    return hat * ratios[f];
  };
  auto clippedAt = [&](std::size_t f, int index, int c) { return codeAt(f, index, c) >= merge.clip_code; };
  auto anyClippedAt = [&](std::size_t f, int index) {
    return clippedAt(f, index, 0) || clippedAt(f, index, 1) || clippedAt(f, index, 2);
  };
  // Bilinear over a frame's four pixels around `pixel`, of each pixel's
  // weighted value and weight (a clipped pixel adds nothing, instead of
  // pulling its neighbours' codes up as interpolated codes would).
  struct Taps {
    int index[4];
    double share[4];
  };
  auto taps = [](const ImageRGB8& image, const glm::dvec2& pixel) {
    const double u0 = std::floor(pixel.x), v0 = std::floor(pixel.y);
    const double fu = pixel.x - u0, fv = pixel.y - v0;
    const int x0 = std::clamp(static_cast<int>(u0), 0, image.width - 1), x1 = std::clamp(static_cast<int>(u0) + 1, 0, image.width - 1);
    const int y0 = std::clamp(static_cast<int>(v0), 0, image.height - 1), y1 = std::clamp(static_cast<int>(v0) + 1, 0, image.height - 1);
    return Taps{{y0 * image.width + x0, y0 * image.width + x1, y1 * image.width + x0, y1 * image.width + x1},
                {(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv}};
  };
  // Frames of a still camera are merged through one pose (the reference's,
  // or the frame's before them): a direction's pixel is found once per
  // distinct view, not once per frame.
  auto sameView = [](const MirrorBallView& a, const MirrorBallView& b) {
    return a.pose.R_cam_from_world == b.pose.R_cam_from_world && a.pose.t_cam_from_world == b.pose.t_cam_from_world &&
           a.center_w == b.center_w && a.radius_m == b.radius_m && a.camera.fx_px == b.camera.fx_px &&
           a.camera.fy_px == b.camera.fy_px && a.camera.cx_px == b.camera.cx_px && a.camera.cy_px == b.camera.cy_px &&
           a.camera.distortion == b.camera.distortion;
  };
  std::vector<std::size_t> view_of(frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    view_of[f] = f;
    for (std::size_t g = 0; g < f; ++g)
      if (sameView(frames[f].view, frames[g].view)) {
        view_of[f] = g;
        break;
      }
  }
  const MirrorBallView& reference = frames.front().view;
  return sampleCube(
      reference, params,
      [&](const glm::dvec3& direction_w, bool& lower_bound) -> std::optional<glm::dvec3> {
        // Per frame and channel: the bilinear value, counted only where none
        // of the four pixels clipped in any channel (so a clipped sun pixel
        // never hides behind its neighbours; and a pixel with one channel
        // clipped has the others wrong as well: a camera's colour matrix
        // mixes its channels, and a clipped Y' decodes through the chroma to
        // channels below the clip, 244 of red for a white sun in NV12),
        // weighted by the bilinear hat
        // weights times the exposure ratio (so pixels lost in the noise
        // count little, and nothing when all four are).
        glm::dvec3 sum(0.0), weight_sum(0.0);
        std::optional<Taps> at_shortest, at_longest;
        bool seen = false;
        thread_local std::vector<std::optional<glm::dvec2>> pixels;  // sampleCube runs on several threads
        pixels.assign(frames.size(), std::nullopt);
        for (std::size_t f = 0; f < frames.size(); ++f) {
          pixels[f] = view_of[f] == f ? reflectedDirectionToPixel(frames[f].view, direction_w, params.normal_iterations)
                                      : pixels[view_of[f]];
          const std::optional<glm::dvec2>& pixel = pixels[f];
          if (!pixel) continue;
          seen = true;
          const Taps t = taps(*frames[f].image, *pixel);
          if (f == shortest) at_shortest = t;
          if (f == longest) at_longest = t;
          for (int c = 0; c < 3; ++c) {
            double value = 0.0, weight = 0.0;
            bool measured = true;
            for (int k = 0; k < 4; ++k) {
              if (t.share[k] <= 0.0) continue;
              measured = measured && !anyClippedAt(f, t.index[k]);
              value += t.share[k] * linearAt(f, t.index[k], c);
              weight += t.share[k] * hatAt(f, t.index[k], c);
            }
            if (!measured || weight <= 0.0) continue;
            sum[c] += weight * value;
            weight_sum[c] += weight;
          }
        }
        if (!seen) return std::nullopt;
        glm::dvec3 value(0.0);
        for (int c = 0; c < 3; ++c) {
          if (weight_sum[c] > 0.0) {
            value[c] = sum[c] / weight_sum[c];
            continue;
          }
          // No frame measured it: the shortest exposure's value, a lower
          // bound where it clipped; else (all dark) the longest's.
          bool shortest_clipped = false;
          if (at_shortest)
            for (int k = 0; k < 4; ++k)
              shortest_clipped = shortest_clipped || (at_shortest->share[k] > 0.0 && anyClippedAt(shortest, at_shortest->index[k]));
          const bool use_shortest = at_shortest && (shortest_clipped || !at_longest);
          const Taps& t = use_shortest ? *at_shortest : *at_longest;
          const std::size_t f = use_shortest ? shortest : longest;
          for (int k = 0; k < 4; ++k) value[c] += t.share[k] * linearAt(f, t.index[k], c);
          if (use_shortest && shortest_clipped) lower_bound = true;
        }
        return value;
      },
      still_clipped);
}

CubeMapRGB probeImageToCubeMap(const MirrorBallView& view, const ImageRGB8& image, const ProbeToCubeParams& params) {
  if (image.empty()) return CubeMapRGB(params.face_size);
  const CameraTransfer& transfer = params.camera_transfer;
  return sampleCube(view, params, [&](const glm::dvec3& direction_w, bool&) -> std::optional<glm::dvec3> {
    const auto pixel = reflectedDirectionToPixel(view, direction_w, params.normal_iterations);
    if (!pixel) return std::nullopt;
    // Encoded values are interpolated, then decoded: what the GPU stage does.
    const glm::dvec3 encoded = sampleEncodedBilinear(image, *pixel);
    return glm::dvec3{decodeCameraValue(transfer, encoded.r), decodeCameraValue(transfer, encoded.g),
                      decodeCameraValue(transfer, encoded.b)};
  });
}

CubeMapRGB probeRadianceToCubeMap(const MirrorBallView& view, const ImageRGBF& linear, const ProbeToCubeParams& params) {
  if (linear.empty()) return CubeMapRGB(params.face_size);
  return sampleCube(view, params, [&](const glm::dvec3& direction_w, bool&) -> std::optional<glm::dvec3> {
    const auto pixel = reflectedDirectionToPixel(view, direction_w, params.normal_iterations);
    if (!pixel) return std::nullopt;
    return sampleLinearBilinear(linear, *pixel);
  });
}

}  // namespace probelight::ibl
