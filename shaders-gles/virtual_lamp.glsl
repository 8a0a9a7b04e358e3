// The virtual lamp's light on the ground at a point, over the room's
// (ibl::lampToRoomRatio), unshadowed: ratio_1m cos(theta) / d^2 times the
// spot's smoothstep of the cosine off its axis. 0 where
// u_lamp_ratio_at_one_metre is (no lamp). For the fragment shaders of the
// ground's composites (ground_composite.frag, virtual_lamp.frag).
//
// Precision: d^2 and d^3 of a lamp 2 cm to 1 m away lie in 4e-4 .. 1; at
// 16-bit mediump their relative steps are 2^-10, a tenth of an 8-bit step
// of the ratio.
#ifdef PL_FRAGMENT_HIGHP
#define LAMP_PLACE highp
#else
#define LAMP_PLACE mediump
#endif
uniform vec3 u_lamp_ratio_at_one_metre;
uniform LAMP_PLACE vec3 u_lamp_w;
uniform LAMP_PLACE vec3 u_spot_direction_w;
uniform LAMP_PLACE vec2 u_spot_cosines;  // outer, inner
uniform float u_spot;                    // 1: a spot; 0: a point light

// The spot's weight toward ground point p (1 for a point light). With
// LAMP_POINT the program is a point light's alone: llvmpipe runs both sides
// of a branch, even on a uniform.
float lampSpot(LAMP_PLACE vec3 ground) {
#ifdef LAMP_POINT
  return 1.0;
#else
  if (u_spot <= 0.0) return 1.0;
  LAMP_PLACE vec3 from_lamp = normalize(ground - u_lamp_w);
  return smoothstep(u_spot_cosines.x, u_spot_cosines.y, dot(from_lamp, u_spot_direction_w));
#endif
}

vec3 lampRatio(LAMP_PLACE vec3 ground) {
  LAMP_PLACE vec3 to_lamp = u_lamp_w - ground;
  LAMP_PLACE float d2 = dot(to_lamp, to_lamp);
  if (!(d2 > 0.0)) return vec3(0.0);
  LAMP_PLACE float cos_over_d2 = max(to_lamp.z, 0.0) / (d2 * sqrt(d2));
  return u_lamp_ratio_at_one_metre * (cos_over_d2 * lampSpot(ground));
}
