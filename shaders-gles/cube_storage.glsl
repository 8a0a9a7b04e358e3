// Cube map faces, storage encoding and bilinear lookups, matching
// ibl/cube_map.cpp. Requires color_transfer.glsl.
//
// Storage: with CUBE_STORAGE_SRGB8 defined, texels are RGBA8 holding
// rgb = linearToSrgb(linear / linear_scale) (so dark values keep ~12x finer
// steps than a linear byte would), a = validity. Otherwise they are linear
// half floats, rgb = linear, a = validity.

vec4 encodeCubeTexel(vec3 linear, float validity, float linear_scale) {
#ifdef CUBE_STORAGE_SRGB8
  return vec4(linearToSrgb(linear / linear_scale), validity);
#else
  return vec4(linear, validity);
#endif
}

vec4 decodeCubeTexel(vec4 stored, float linear_scale) {
#ifdef CUBE_STORAGE_SRGB8
  return vec4(srgbToLinear(stored.rgb) * linear_scale, stored.a);
#else
  return stored;
#endif
}

// Face (0..5, GL order) and (s, t) that GL samples for direction d. Ties go
// to z, then y, then x, as ibl::directionToCubeCoord.
vec3 cubeFaceCoord(vec3 d) {
  vec3 a = abs(d);
  float face;
  float sc;
  float tc;
  float ma;
  if (a.z >= a.x && a.z >= a.y) {
    ma = a.z;
    face = d.z >= 0.0 ? 4.0 : 5.0;
    sc = d.z >= 0.0 ? d.x : -d.x;
    tc = -d.y;
  } else if (a.y >= a.x) {
    ma = a.y;
    face = d.y >= 0.0 ? 2.0 : 3.0;
    sc = d.x;
    tc = d.y >= 0.0 ? d.z : -d.z;
  } else {
    ma = a.x;
    face = d.x >= 0.0 ? 0.0 : 1.0;
    sc = d.x >= 0.0 ? -d.z : d.z;
    tc = -d.y;
  }
  return vec3(face, 0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0));
}

// Unnormalised direction of (s, t) on `face`: inverse of cubeFaceCoord.
vec3 cubeFaceDirection(float face, vec2 st) {
  vec2 c = 2.0 * st - 1.0;
  if (face < 0.5) return vec3(1.0, -c.y, -c.x);
  if (face < 1.5) return vec3(-1.0, -c.y, c.x);
  if (face < 2.5) return vec3(c.x, 1.0, c.y);
  if (face < 3.5) return vec3(c.x, -1.0, -c.y);
  if (face < 4.5) return vec3(c.x, -c.y, 1.0);
  return vec3(-c.x, -c.y, -1.0);
}

// Texel (x, y) of `face`, decoded. The map is NEAREST-filtered and this asks
// for the texel's exact centre, which lies strictly inside its face, so
// seamless (ES3) and non-seamless (GLES2) samplers return the same texel.
vec4 fetchCubeTexel(samplerCube map, float face, vec2 texel, float face_size, float linear_scale) {
  return decodeCubeTexel(textureCube(map, cubeFaceDirection(face, (texel + 0.5) / face_size)), linear_scale);
}

// Bilinear lookup within the face GL picks, clamped to that face's edge, as
// ibl::CubeMapRGB::sampleBilinear: filtering is done here on decoded linear
// values (hardware filtering of sRGB bytes would blend encoded values), and
// it behaves like a GLES2 non-seamless sampler on every GPU.
vec4 sampleCubeBilinear(samplerCube map, vec3 direction, float face_size, float linear_scale) {
  vec3 coord = cubeFaceCoord(direction);
  vec2 uv = coord.yz * face_size - 0.5;
  vec2 base = floor(uv);
  vec2 f = uv - base;
  float last = face_size - 1.0;
  vec2 lo = clamp(base, 0.0, last);
  vec2 hi = clamp(base + 1.0, 0.0, last);
  vec4 top = mix(fetchCubeTexel(map, coord.x, vec2(lo.x, lo.y), face_size, linear_scale),
                 fetchCubeTexel(map, coord.x, vec2(hi.x, lo.y), face_size, linear_scale), f.x);
  vec4 bottom = mix(fetchCubeTexel(map, coord.x, vec2(lo.x, hi.y), face_size, linear_scale),
                    fetchCubeTexel(map, coord.x, vec2(hi.x, hi.y), face_size, linear_scale), f.x);
  return mix(top, bottom, f.y);
}
