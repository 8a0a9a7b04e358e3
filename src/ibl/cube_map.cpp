#include "ibl/cube_map.hpp"

#include <algorithm>
#include <cmath>

namespace probelight::ibl {

namespace {

enum Face { kPosX = 0, kNegX = 1, kPosY = 2, kNegY = 3, kPosZ = 4, kNegZ = 5 };

// Integral of the area element dA / (1 + x^2 + y^2)^(3/2) over [0,x]x[0,y] on
// the z = 1 plane: the solid angle of that rectangle seen from the origin.
double cornerSolidAngle(double x, double y) { return std::atan2(x * y, std::sqrt(x * x + y * y + 1.0)); }

bool isUsableDirection(const glm::dvec3& d) {
  return std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z) && (d.x != 0.0 || d.y != 0.0 || d.z != 0.0);
}

glm::vec3 lerp(const glm::vec3& a, const glm::vec3& b, float f) { return a + (b - a) * f; }

}  // namespace

glm::dvec3 cubeCoordToDirection(const CubeTexelCoord& coord) {
  const double sc = 2.0 * coord.s - 1.0;
  const double tc = 2.0 * coord.t - 1.0;
  glm::dvec3 d;
  // Inverse of the GLES 2.0 table in directionToCubeCoord.
  switch (coord.face) {
    case kPosX: d = {1.0, -tc, -sc}; break;
    case kNegX: d = {-1.0, -tc, sc}; break;
    case kPosY: d = {sc, 1.0, tc}; break;
    case kNegY: d = {sc, -1.0, -tc}; break;
    case kPosZ: d = {sc, -tc, 1.0}; break;
    default: d = {-sc, -tc, -1.0}; break;
  }
  return glm::normalize(d);
}

CubeTexelCoord directionToCubeCoord(const glm::dvec3& direction) {
  // NaN, Inf or zero has no face: NaN fails every comparison below and would
  // come out as face -X with s, t = NaN, which callers turn into texel indices
  // (a NaN cast to int is undefined). A defined answer instead: the centre of
  // face +X (CubeTexelCoord's defaults); samplers return 0 for such directions.
  if (!isUsableDirection(direction)) return CubeTexelCoord{};
  const double ax = std::abs(direction.x);
  const double ay = std::abs(direction.y);
  const double az = std::abs(direction.z);
  CubeTexelCoord coord;
  double sc = 0.0;
  double tc = 0.0;
  double ma = 0.0;
  // Ties go to z, then y, then x, as Mesa's llvmpipe (lp_build_cube_lookup)
  // does, so edge and corner directions land on the face the GPU samples.
  if (az >= ax && az >= ay) {
    ma = az;
    coord.face = direction.z >= 0.0 ? kPosZ : kNegZ;
    sc = direction.z >= 0.0 ? direction.x : -direction.x;
    tc = -direction.y;
  } else if (ay >= ax) {
    ma = ay;
    coord.face = direction.y >= 0.0 ? kPosY : kNegY;
    sc = direction.x;
    tc = direction.y >= 0.0 ? direction.z : -direction.z;
  } else {
    ma = ax;
    coord.face = direction.x >= 0.0 ? kPosX : kNegX;
    sc = direction.x >= 0.0 ? -direction.z : direction.z;
    tc = -direction.y;
  }
  coord.s = 0.5 * (sc / ma + 1.0);
  coord.t = 0.5 * (tc / ma + 1.0);
  return coord;
}

glm::dvec3 cubeTexelCenterDirection(int face, int x, int y, int face_size) {
  const double n = static_cast<double>(face_size);
  return cubeCoordToDirection({face, (x + 0.5) / n, (y + 0.5) / n});
}

double cubeTexelSolidAngle(int x, int y, int face_size) {
  const double n = static_cast<double>(face_size);
  // Texel corners in face coordinates [-1, 1]; the solid angle is the same on
  // every face, and the formula is symmetric so the s/t orientation is moot.
  const double x0 = 2.0 * x / n - 1.0;
  const double x1 = 2.0 * (x + 1) / n - 1.0;
  const double y0 = 2.0 * y / n - 1.0;
  const double y1 = 2.0 * (y + 1) / n - 1.0;
  return cornerSolidAngle(x1, y1) - cornerSolidAngle(x0, y1) - cornerSolidAngle(x1, y0) + cornerSolidAngle(x0, y0);
}

CubeMapRGB::CubeMapRGB(int size) : face_size(size) {
  for (auto& face : faces) face.assign(static_cast<size_t>(size) * static_cast<size_t>(size), glm::vec3(0.0f));
}

glm::vec3 CubeMapRGB::sampleNearest(const glm::dvec3& direction) const {
  if (face_size <= 0 || !isUsableDirection(direction)) return glm::vec3(0.0f);
  const CubeTexelCoord c = directionToCubeCoord(direction);
  const int x = std::clamp(static_cast<int>(std::floor(c.s * face_size)), 0, face_size - 1);
  const int y = std::clamp(static_cast<int>(std::floor(c.t * face_size)), 0, face_size - 1);
  return texel(c.face, x, y);
}

glm::vec3 CubeMapRGB::sampleBilinear(const glm::dvec3& direction) const {
  if (face_size <= 0 || !isUsableDirection(direction)) return glm::vec3(0.0f);
  const CubeTexelCoord c = directionToCubeCoord(direction);
  // GL puts texel centres at integer + 0.5, hence the half-texel shift.
  const double u = c.s * face_size - 0.5;
  const double v = c.t * face_size - 0.5;
  const double u_floor = std::floor(u);
  const double v_floor = std::floor(v);
  const float fu = static_cast<float>(u - u_floor);
  const float fv = static_cast<float>(v - v_floor);
  const int last = face_size - 1;
  const int x0 = std::clamp(static_cast<int>(u_floor), 0, last);
  const int x1 = std::clamp(static_cast<int>(u_floor) + 1, 0, last);
  const int y0 = std::clamp(static_cast<int>(v_floor), 0, last);
  const int y1 = std::clamp(static_cast<int>(v_floor) + 1, 0, last);
  const glm::vec3 top = lerp(texel(c.face, x0, y0), texel(c.face, x1, y0), fu);
  const glm::vec3 bottom = lerp(texel(c.face, x0, y1), texel(c.face, x1, y1), fu);
  return lerp(top, bottom, fv);
}

}  // namespace probelight::ibl
