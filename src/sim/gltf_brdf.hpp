// The glTF 2.0 metallic-roughness BRDF as the simulator evaluates it, its
// importance sampling, and the material's inputs at a hit read from the
// model's textures: the oracle's own code, written from the glTF 2.0
// specification (Appendix B, "BRDF Implementation"), never from src/ibl,
// which it checks.
//
//   f = mix(dielectric, metal, metallic)
//   dielectric = fresnel_mix(ior 1.5: F0 = 0.04, base = c / pi, layer = V D)
//              = (1 - F_d) c / pi + F_d V D,  F_d = 0.04 + 0.96 (1 - |v.h|)^5
//   metal = F_m V D,  F_m = c + (1 - c) (1 - |v.h|)^5
//   D = alpha^2 chi(n.h) / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2)  (GGX), alpha = roughness^2
//   V = chi(h.l) / (|n.l| + sqrt(alpha^2 + (1 - alpha^2)(n.l)^2))
//     * chi(h.v) / (|n.v| + sqrt(alpha^2 + (1 - alpha^2)(n.v)^2))
// V is Smith's G divided by 4 |n.l| |n.v|. The formula above is the one
// Appendix B writes, which it calls "the separable form of the Smith joint
// masking-shadowing function"; the height-correlated form (Heitz 2014, what
// Khronos' sample viewer uses), V = 0.5 / (n.l sqrt(alpha^2 + (1 - alpha^2)
// (n.v)^2) + n.v sqrt(alpha^2 + (1 - alpha^2)(n.l)^2)), is there too
// (SmithVisibility); the two agree where v or l faces the surface and part
// for rough surfaces seen and lit at grazing angles (12% at roughness 1, 80
// deg). c is the base colour in linear RGB.
//
// The spec's fresnel_mix takes (1 - F(v.h)) from the diffuse per microfacet,
// not the specular layer's directional albedo: a smooth white dielectric
// seen at a grazing angle sends back more than it receives (1.2 at 75 deg,
// roughness 0.05). That is the spec's BRDF, and so the oracle's.
//
// Left out for now: normal maps (the shading normal is the mesh's), the
// occlusion texture (an approximation of what the oracle traces), and the
// material extensions (clearcoat, transmission, ...).
#pragma once

#include <glm/glm.hpp>

#include "model/mesh_model.hpp"
#include "sim/triangle_bvh.hpp"

namespace probelight::sim {

// A material's inputs at one point of a surface.
struct GltfSurface {
  glm::dvec3 base_color{1.0};  // linear RGB: factor x decoded texture x vertex colour
  double metallic = 1.0;       // [0, 1]
  double roughness = 1.0;      // [0, 1], perceptual: alpha = roughness^2
  glm::dvec3 emissive{0.0};    // linear RGB: factor x decoded texture
  double alpha = 1.0;          // coverage: factor x texture x vertex colour; what alpha_mode does with it is the caller's
};

namespace gltf_brdf {

// The smallest GGX alpha used. Roughness 0 would make D a delta (infinite
// at n = h, zero elsewhere): evaluate() would return 0 or inf and the VNDF
// sampler would divide 0 by 0. At 1e-3 the peak 1/(pi alpha^2) is 3.2e5 and
// the lobe about a milliradian wide, narrower than anything the simulator
// resolves (a pixel of its frames is ~2 mrad), so a mirror looks a mirror,
// while every quantity stays finite: alpha^4 = 1e-12 is far from underflow
// and the cancellation in 1 - (n.h)^2 costs 1e-10 of D, relative.
constexpr double kMinAlpha = 1e-3;

// max(roughness^2, kMinAlpha), roughness taken into [0, 1].
double ggxAlpha(double roughness);

enum class SmithVisibility {
  kSeparable,        // the spec's Appendix B formula
  kHeightCorrelated  // Heitz 2014's, as the Khronos sample viewer has it
};

// f(v, l) (n.l), per steradian, for unit n, v (towards the viewer) and l
// (towards the light). 0 where l or v is below the horizon of n: a caller
// shading a back face of a double-sided material flips n first.
glm::dvec3 evaluate(const glm::dvec3& n, const glm::dvec3& v, const glm::dvec3& l, const GltfSurface& surface,
                    SmithVisibility visibility = SmithVisibility::kSeparable);

struct BrdfSample {
  glm::dvec3 l{0.0, 0.0, 1.0};  // unit
  double pdf = 0.0;             // per steradian; 0: no sample (use none)
};

// A direction drawn from a mixture of two densities, with u1, u2, u3
// uniform in [0, 1): with probability specularProbability() the GGX
// distribution of visible normals (Heitz, "Sampling the GGX distribution of
// visible normals", JCGT 2018) reflected about v, else the cosine-weighted
// hemisphere. The pdf is the mixture's (the one-sample MIS balance
// heuristic), so evaluate() / pdf is the estimator's weight. A GGX sample
// can fall below the horizon (a visible microfacet that reflects into the
// surface): it keeps its density there and evaluate() gives it 0, so the
// estimate stays unbiased; the pdf integrates to 1 over the sphere. The
// sampler uses only G1 and D, so it serves either SmithVisibility.
BrdfSample sampleDirection(const glm::dvec3& n, const glm::dvec3& v, const GltfSurface& surface, double u1, double u2,
                           double u3);
// The density sampleDirection draws l with, per steradian.
double pdf(const glm::dvec3& n, const glm::dvec3& v, const glm::dvec3& l, const GltfSurface& surface);

// How often sampleDirection takes the GGX lobe: the specular share of the
// albedo guessed from Schlick's Fresnel at n.v, kept in [0.1, 0.9] so that
// neither density is ever starved (a poor guess costs variance, not bias,
// and the weight stays bounded where the other lobe dominates).
double specularProbability(double n_dot_v, const GltfSurface& surface);

}  // namespace gltf_brdf

// ---- The material's textures, read by the simulator's own sampler ----

enum class TexelEncoding { kLinear, kSrgb };

// KHR_texture_transform: uv' = T R S uv, with R turning (u, v) into
// (cos r u + sin r v, -sin r u + cos r v): the extension's "counter-
// clockwise" in the texture's frame, whose v points down; its worked example
// (offset (0, 1), rotation pi/2, scale 0.5 shows the lower-left quadrant)
// holds with this sign.
glm::dvec2 textureTransform(const model::TextureSlot& slot, const glm::dvec2& uv);

// The texture's value at the mesh's `uv` (before the slot's transform):
// bilinear between texel centres (nearest where the sampler's magFilter is
// NEAREST), the sampler's wrap modes per texel as GL applies them, and sRGB
// texels decoded to linear before they are mixed, as a GPU's sRGB texture
// does; alpha is linear in either encoding. Texel (0, 0) is the image's
// top-left, at uv (0, 0), as glTF has it. An empty image reads as 1.
glm::dvec4 sampleTexture(const model::TextureImage& image, const model::TextureSlot& slot, const glm::dvec2& uv,
                         TexelEncoding encoding);

// The material's inputs at a hit: base colour factor x sRGB base colour
// texture x vertex colour, metallic and roughness factors x the metallic-
// roughness texture's B and G, emissive factor x sRGB emissive texture,
// alpha. Each texture reads the UV set its slot names (TEXCOORD_0 or _1).
// A hit without a material (or with one out of range) gets glTF's default:
// white, metallic 1, roughness 1.
GltfSurface surfaceAt(const model::MeshModel& model, const TriangleHit& hit);

}  // namespace probelight::sim
