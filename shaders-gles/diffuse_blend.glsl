// Temporal blending of the diffuse map, shared by the passes that write it
// (cosine_irradiance.frag's north pass, sh9_irradiance.frag). Requires
// cube_storage.glsl.
//
// The result is u_new_weight * fresh + (1 - u_new_weight) * previous in
// linear light: the previous map is read back decoded with its own scale
// (a ping-pong partner texture, never the one being written), so the 8-bit
// path blends light, not sRGB-encoded bytes, and a change of linear_scale
// between updates is harmless. The weight is uniform over the draw, so the
// branch is too; at weight 1 the previous map is not read at all.
uniform samplerCube u_previous;
uniform float u_previous_scale;
// The previous map's units into the fresh one's, per channel: the camera's
// exposure and white balance moved between the two frames
// (stages/frame_response.hpp), so light is blended with light.
uniform vec3 u_previous_units;
uniform float u_new_weight;

// `direction` is the centre of the texel being written; the previous map has
// the same face size and is NEAREST-filtered, so this reads exactly that
// texel (the centre lies strictly inside its face on every sampler).
vec4 blendWithPrevious(vec4 fresh, vec3 direction) {
  if (u_new_weight >= 1.0) return fresh;
  vec4 previous = decodeCubeTexel(textureCube(u_previous, direction), u_previous_scale);
  previous.rgb *= u_previous_units;
  return mix(previous, fresh, u_new_weight);
}
