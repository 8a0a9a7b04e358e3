// OpenCV's 5-term distortion of a normalised point, term for term as
// ibl/camera_projection.cpp. k1k2p1p2 = (k1, k2, p1, p2).
vec2 distortNormalized(vec2 p, vec4 k1k2p1p2, float k3) {
  float r2 = dot(p, p);
  float radial = 1.0 + r2 * (k1k2p1p2.x + r2 * (k1k2p1p2.y + r2 * k3));
  float p1 = k1k2p1p2.z;
  float p2 = k1k2p1p2.w;
  return vec2(p.x * radial + 2.0 * p1 * p.x * p.y + p2 * (r2 + 2.0 * p.x * p.x),
              p.y * radial + p1 * (r2 + 2.0 * p.y * p.y) + 2.0 * p2 * p.x * p.y);
}
