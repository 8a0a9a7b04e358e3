#include "sim/gltf_brdf.hpp"
#include "core/math_constants.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace probelight::sim {
namespace {

constexpr double kDielectricF0 = 0.04;  // ((1 - ior) / (1 + ior))^2 for ior 1.5

// Into [0, 1]; NaN to 0, so a broken input cannot poison a whole frame.
double unitInterval(double x) { return x >= 0.0 ? (x <= 1.0 ? x : 1.0) : 0.0; }

double luminance(const glm::dvec3& rgb) { return glm::dot(rgb, glm::dvec3(0.2126, 0.7152, 0.0722)); }

double schlickWeight(double cos_theta) {
  const double m = 1.0 - unitInterval(cos_theta);
  const double m2 = m * m;
  return m2 * m2 * m;
}

double ggxD(double n_dot_h, double alpha) {
  if (n_dot_h <= 0.0) return 0.0;
  const double a2 = alpha * alpha;
  const double d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
  return a2 / (kPi * d * d);
}

// sqrt(alpha^2 + (1 - alpha^2) c^2): the Smith term's root, shared by V and G1.
double smithRoot(double cos_theta, double alpha) {
  const double a2 = alpha * alpha;
  return std::sqrt(a2 + (1.0 - a2) * cos_theta * cos_theta);
}

// Smith's masking of one direction, for the VNDF's density.
double smithG1(double n_dot_v, double alpha) { return 2.0 * n_dot_v / (n_dot_v + smithRoot(n_dot_v, alpha)); }

// An orthonormal frame around unit n (Duff et al., JCGT 2017): no branch
// that flips at some direction, and no cancellation near n = -z.
struct Frame {
  glm::dvec3 t, b, n;
  explicit Frame(const glm::dvec3& normal) : n(normal) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double c = n.x * n.y * a;
    t = glm::dvec3(1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = glm::dvec3(c, sign + n.y * n.y * a, -n.y);
  }
  glm::dvec3 toLocal(const glm::dvec3& w) const { return {glm::dot(w, t), glm::dot(w, b), glm::dot(w, n)}; }
  glm::dvec3 toWorld(const glm::dvec3& w) const { return w.x * t + w.y * b + w.z * n; }
};

// Heitz 2018, listing 1, for an isotropic alpha: a microfacet normal drawn
// with density D_v(h) = G1(v) max(0, v.h) D(h) / (n.v), v in the local frame.
glm::dvec3 sampleVisibleNormal(const glm::dvec3& v_local, double alpha, double u1, double u2) {
  const glm::dvec3 vh = glm::normalize(glm::dvec3(alpha * v_local.x, alpha * v_local.y, v_local.z));
  const double length_squared = vh.x * vh.x + vh.y * vh.y;
  const glm::dvec3 t1 =
      length_squared > 0.0 ? glm::dvec3(-vh.y, vh.x, 0.0) / std::sqrt(length_squared) : glm::dvec3(1.0, 0.0, 0.0);
  const glm::dvec3 t2 = glm::cross(vh, t1);
  const double r = std::sqrt(unitInterval(u1));
  const double phi = 2.0 * kPi * u2;
  const double p1 = r * std::cos(phi);
  double p2 = r * std::sin(phi);
  const double s = 0.5 * (1.0 + vh.z);
  p2 = (1.0 - s) * std::sqrt(std::max(0.0, 1.0 - p1 * p1)) + s * p2;
  const glm::dvec3 nh = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
  return glm::normalize(glm::dvec3(alpha * nh.x, alpha * nh.y, std::max(0.0, nh.z)));
}

// sRGB (IEC 61966-2-1) code to linear, for the 256 codes of an 8-bit texel.
const std::array<double, 256>& srgbToLinear() {
  static const std::array<double, 256> table = [] {
    std::array<double, 256> t{};
    for (int code = 0; code < 256; ++code) {
      const double c = code / 255.0;
      t[static_cast<std::size_t>(code)] = c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
    }
    return t;
  }();
  return table;
}

// The texel a (whole-numbered) coordinate reads under a wrap mode, as GL
// wraps texel indices. Done in double so that a huge or negative coordinate
// never reaches an int conversion out of range.
int wrapTexel(double i, int size, model::TextureWrap wrap) {
  const double n = size;
  double m = i;
  switch (wrap) {
    case model::TextureWrap::kClampToEdge: break;
    case model::TextureWrap::kRepeat: m = i - n * std::floor(i / n); break;
    case model::TextureWrap::kMirroredRepeat: {
      const double period = 2.0 * n;
      const double k = i - period * std::floor(i / period);  // [0, 2n)
      m = k < n ? k : period - 1.0 - k;
      break;
    }
  }
  return static_cast<int>(std::clamp(m, 0.0, n - 1.0));
}

glm::dvec4 texel(const model::TextureImage& image, int x, int y, TexelEncoding encoding) {
  const std::uint8_t* p =
      &image.rgba[(static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width) + static_cast<std::size_t>(x)) * 4];
  if (encoding == TexelEncoding::kSrgb) {
    const auto& decode = srgbToLinear();
    return {decode[p[0]], decode[p[1]], decode[p[2]], p[3] / 255.0};
  }
  return glm::dvec4(p[0], p[1], p[2], p[3]) / 255.0;
}

glm::dvec4 sampleSlot(const model::MeshModel& model, const model::TextureSlot& slot, const TriangleHit& hit,
                      TexelEncoding encoding) {
  if (!slot.present() || slot.image >= static_cast<int>(model.images.size())) return glm::dvec4(1.0);
  return sampleTexture(model.images[static_cast<std::size_t>(slot.image)], slot, slot.texcoord == 1 ? hit.uv1 : hit.uv0,
                       encoding);
}

}  // namespace

namespace gltf_brdf {

double ggxAlpha(double roughness) {
  const double r = unitInterval(roughness);
  return std::max(r * r, kMinAlpha);
}

glm::dvec3 evaluate(const glm::dvec3& n, const glm::dvec3& v, const glm::dvec3& l, const GltfSurface& surface,
                    SmithVisibility visibility_form) {
  const double n_dot_l = glm::dot(n, l), n_dot_v = glm::dot(n, v);
  if (!(n_dot_l > 0.0 && n_dot_v > 0.0)) return glm::dvec3(0.0);
  // n.l > 0 and n.v > 0 keep v + l away from zero.
  const glm::dvec3 h = glm::normalize(v + l);
  const double v_dot_h = glm::dot(v, h), l_dot_h = glm::dot(l, h);
  const double alpha = ggxAlpha(surface.roughness);
  const double d = ggxD(glm::dot(n, h), alpha);
  double visibility = 0.0;
  if (l_dot_h > 0.0 && v_dot_h > 0.0) {
    visibility = visibility_form == SmithVisibility::kSeparable
                     ? 1.0 / ((n_dot_l + smithRoot(n_dot_l, alpha)) * (n_dot_v + smithRoot(n_dot_v, alpha)))
                     : 0.5 / (n_dot_l * smithRoot(n_dot_v, alpha) + n_dot_v * smithRoot(n_dot_l, alpha));
  }
  const double specular = visibility * d;
  const double schlick = schlickWeight(std::abs(v_dot_h));
  const glm::dvec3 base = glm::clamp(surface.base_color, 0.0, 1.0);
  const double metallic = unitInterval(surface.metallic);
  const double fresnel_dielectric = kDielectricF0 + (1.0 - kDielectricF0) * schlick;
  const glm::dvec3 fresnel_metal = base + (1.0 - base) * schlick;
  const glm::dvec3 dielectric = (1.0 - fresnel_dielectric) * base / kPi + glm::dvec3(fresnel_dielectric * specular);
  const glm::dvec3 metal = fresnel_metal * specular;
  return glm::mix(dielectric, metal, metallic) * n_dot_l;
}

double specularProbability(double n_dot_v, const GltfSurface& surface) {
  const glm::dvec3 base = glm::clamp(surface.base_color, 0.0, 1.0);
  const double metallic = unitInterval(surface.metallic);
  const double schlick = schlickWeight(n_dot_v);
  const glm::dvec3 f0 = glm::mix(glm::dvec3(kDielectricF0), base, metallic);
  const double specular = luminance(f0 + (1.0 - f0) * schlick);
  const double diffuse = (1.0 - metallic) * luminance(base) * (1.0 - (kDielectricF0 + (1.0 - kDielectricF0) * schlick));
  const double p = specular + diffuse > 0.0 ? specular / (specular + diffuse) : 0.5;
  return std::clamp(p, 0.1, 0.9);
}

double pdf(const glm::dvec3& n, const glm::dvec3& v, const glm::dvec3& l, const GltfSurface& surface) {
  const double n_dot_v = glm::dot(n, v);
  if (!(n_dot_v > 0.0)) return 0.0;
  const double p_specular = specularProbability(n_dot_v, surface);
  const double cosine_pdf = std::max(0.0, glm::dot(n, l)) / kPi;
  double specular_pdf = 0.0;
  const glm::dvec3 half = v + l;
  const double half_length = glm::length(half);
  if (half_length > 0.0) {
    // D_v(h) / (4 v.h), with D_v = G1(v) (v.h) D(h) / (n.v): the v.h cancel
    // (v.h = (1 + v.l) / |v + l| > 0 for every l but -v).
    const double alpha = ggxAlpha(surface.roughness);
    specular_pdf = smithG1(n_dot_v, alpha) * ggxD(glm::dot(n, half) / half_length, alpha) / (4.0 * n_dot_v);
  }
  return p_specular * specular_pdf + (1.0 - p_specular) * cosine_pdf;
}

BrdfSample sampleDirection(const glm::dvec3& n, const glm::dvec3& v, const GltfSurface& surface, double u1, double u2,
                           double u3) {
  BrdfSample sample;
  const double n_dot_v = glm::dot(n, v);
  if (!(n_dot_v > 0.0)) return sample;
  const Frame frame(n);
  glm::dvec3 l_local;
  if (u3 < specularProbability(n_dot_v, surface)) {
    const glm::dvec3 v_local = frame.toLocal(v);
    const glm::dvec3 h = sampleVisibleNormal(v_local, ggxAlpha(surface.roughness), u1, u2);
    l_local = 2.0 * glm::dot(v_local, h) * h - v_local;
  } else {
    const double r = std::sqrt(unitInterval(u1)), phi = 2.0 * kPi * u2;
    l_local = glm::dvec3(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1.0 - r * r)));
  }
  sample.l = glm::normalize(frame.toWorld(l_local));
  sample.pdf = pdf(n, v, sample.l, surface);
  if (!std::isfinite(sample.pdf)) sample.pdf = 0.0;
  return sample;
}

}  // namespace gltf_brdf

glm::dvec2 textureTransform(const model::TextureSlot& slot, const glm::dvec2& uv) {
  const double r = slot.uv_rotation_rad;
  const double c = std::cos(r), s = std::sin(r);
  const glm::dvec2 scaled = glm::dvec2(slot.uv_scale) * uv;
  return glm::dvec2(c * scaled.x + s * scaled.y, -s * scaled.x + c * scaled.y) + glm::dvec2(slot.uv_offset);
}

glm::dvec4 sampleTexture(const model::TextureImage& image, const model::TextureSlot& slot, const glm::dvec2& uv,
                         TexelEncoding encoding) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgba.size() < static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 4)
    return glm::dvec4(1.0);
  glm::dvec2 st = textureTransform(slot, uv);
  if (!std::isfinite(st.x) || !std::isfinite(st.y)) st = glm::dvec2(0.0);
  const double x = st.x * image.width, y = st.y * image.height;
  if (slot.nearest)
    return texel(image, wrapTexel(std::floor(x), image.width, slot.wrap_s),
                 wrapTexel(std::floor(y), image.height, slot.wrap_t), encoding);
  // Texel centres sit at half-integers: the four around (x, y).
  const double xc = x - 0.5, yc = y - 0.5;
  const double x0 = std::floor(xc), y0 = std::floor(yc);
  const double fx = xc - x0, fy = yc - y0;
  const int left = wrapTexel(x0, image.width, slot.wrap_s), right = wrapTexel(x0 + 1.0, image.width, slot.wrap_s);
  const int top = wrapTexel(y0, image.height, slot.wrap_t), bottom = wrapTexel(y0 + 1.0, image.height, slot.wrap_t);
  const glm::dvec4 upper = glm::mix(texel(image, left, top, encoding), texel(image, right, top, encoding), fx);
  const glm::dvec4 lower = glm::mix(texel(image, left, bottom, encoding), texel(image, right, bottom, encoding), fx);
  return glm::mix(upper, lower, fy);
}

GltfSurface surfaceAt(const model::MeshModel& model, const TriangleHit& hit) {
  static const model::Material kDefaultMaterial;  // glTF's: white, metallic 1, roughness 1
  const model::Material& material = hit.material >= 0 && hit.material < static_cast<int>(model.materials.size())
                                        ? model.materials[static_cast<std::size_t>(hit.material)]
                                        : kDefaultMaterial;
  GltfSurface surface;
  const glm::dvec4 base = glm::dvec4(material.base_color_factor) *
                          sampleSlot(model, material.base_color, hit, TexelEncoding::kSrgb) * hit.color;
  surface.base_color = glm::clamp(glm::dvec3(base), 0.0, 1.0);
  surface.alpha = unitInterval(base.a);
  const glm::dvec4 metallic_roughness = sampleSlot(model, material.metallic_roughness, hit, TexelEncoding::kLinear);
  surface.roughness = unitInterval(material.roughness_factor * metallic_roughness.g);
  surface.metallic = unitInterval(material.metallic_factor * metallic_roughness.b);
  surface.emissive = glm::max(glm::dvec3(material.emissive_factor) *
                                  glm::dvec3(sampleSlot(model, material.emissive, hit, TexelEncoding::kSrgb)),
                              0.0);
  return surface;
}

}  // namespace probelight::sim
