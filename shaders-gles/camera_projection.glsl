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

// distortNormalized(c + d) - distortNormalized(c) for a small offset d,
// written so that every term is a small quantity times an O(1) one: at
// 16-bit mediump the difference of the two O(1) values would keep only
// ~2^-11 of their size (0.2 px of a 640 px image), this keeps ~2^-11 of
// |d|'s. center_r2 = |c|^2 and center_radial = 1 + k1 r2 + k2 r2^2 + k3 r2^3
// at c come from the CPU, in double.
vec2 distortionDelta(vec2 c, vec2 d, float center_r2, float center_radial, vec4 k1k2p1p2, float k3) {
  vec2 p = c + d;
  float r2_delta = dot(d, c + p);  // |p|^2 - |c|^2
  float r2 = center_r2 + r2_delta;
  // R(r2) - R(center_r2) = (r2 - center_r2) (k1 + k2 (r2 + center_r2) + k3 (r2^2 + r2 center_r2 + center_r2^2))
  float radial_delta =
      r2_delta * (k1k2p1p2.x + k1k2p1p2.y * (r2 + center_r2) + k3 * (r2 * r2 + r2 * center_r2 + center_r2 * center_r2));
  float p1 = k1k2p1p2.z;
  float p2 = k1k2p1p2.w;
  float xy_delta = d.x * p.y + c.x * d.y;  // p.x p.y - c.x c.y
  vec2 squares_delta = d * (c + p);        // p^2 - c^2, per axis
  return d * (center_radial + radial_delta) + c * radial_delta +
         vec2(2.0 * p1 * xy_delta + p2 * (r2_delta + 2.0 * squares_delta.x),
              p1 * (r2_delta + 2.0 * squares_delta.y) + 2.0 * p2 * xy_delta);
}
