// Cube maps in the world frame W. Face order and per-face (s, t) axes follow
// the OpenGL ES cube map table exactly (GL_TEXTURE_CUBE_MAP_POSITIVE_X + face:
// +X, -X, +Y, -Y, +Z, -Z), so a CubeMapRGB uploaded face by face with
// glTexImage2D (row 0 = t near 0) is sampled by GLSL textureCube(dir) at the
// same direction the CPU uses here. World +Z (up) is the +Z face.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include <glm/glm.hpp>

namespace probelight::ibl {

constexpr int kCubeFaceCount = 6;

struct CubeTexelCoord {
  int face = 0;    // 0..5 in GL order
  double s = 0.5;  // texture coordinate in [0, 1] along the face's s axis
  double t = 0.5;  // texture coordinate in [0, 1] along the face's t axis
};

// Unit direction at texture coordinate (s, t) of `face`.
glm::dvec3 cubeCoordToDirection(const CubeTexelCoord& coord);
// Direction (any length > 0) to the face and (s, t) that GL would sample.
// Where two or three components tie in magnitude (face edges and corners) the
// face is chosen as Mesa llvmpipe does: z first, then y, then x.
// A non-finite or zero direction gives the default coord (face 0, s = t = 0.5).
CubeTexelCoord directionToCubeCoord(const glm::dvec3& direction);
// Centre of texel (x, y) of a face of size n: s = (x + 0.5) / n, t = (y + 0.5) / n.
glm::dvec3 cubeTexelCenterDirection(int face, int x, int y, int face_size);
// Solid angle (steradians) subtended by texel (x, y); sums to 4*pi over the cube.
double cubeTexelSolidAngle(int x, int y, int face_size);

// Whether texel `index` (y * n + x) of `face` is one the ball showed: a
// validity list holds face * n^2 + y * n + x, and a texel the ball does not
// show is < 0.5 there. A missing or mis-sized list means all are seen.
inline bool texelSeen(const std::vector<float>* validity, int face, std::size_t index, int face_size) {
  const std::size_t per_face = static_cast<std::size_t>(face_size) * face_size;
  if (validity == nullptr || validity->size() != kCubeFaceCount * per_face) return true;
  return (*validity)[static_cast<std::size_t>(face) * per_face + index] >= 0.5f;
}

// Linear-light RGB cube map on the CPU (the reference the GPU is checked
// against). faces[f][y * face_size + x] is texel (x, y) of face f.
struct CubeMapRGB {
  int face_size = 0;
  std::array<std::vector<glm::vec3>, kCubeFaceCount> faces;

  explicit CubeMapRGB(int size = 0);
  glm::vec3& texel(int face, int x, int y) { return faces[face][static_cast<size_t>(y) * face_size + x]; }
  const glm::vec3& texel(int face, int x, int y) const { return faces[face][static_cast<size_t>(y) * face_size + x]; }
  // Both lookups return 0 for a non-finite or zero direction (and an empty map).
  // Nearest-texel lookup, as GL_NEAREST does.
  glm::vec3 sampleNearest(const glm::dvec3& direction) const;
  // Bilinear lookup within the face GL picks, clamped to the face edge, as a
  // GLES2 (non-seamless) cube sampler with GL_LINEAR and CLAMP_TO_EDGE does.
  glm::vec3 sampleBilinear(const glm::dvec3& direction) const;
};

}  // namespace probelight::ibl
