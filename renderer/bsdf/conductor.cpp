#include "bsdf/fresnel.h"
#include "bsdf/microfacet.h"
#include "bsdf/models.h"

namespace omega {

namespace {
bool is_smooth(const ConductorBsdf& b) { return b.alpha_u == 0 && b.alpha_v == 0; }
Microfacet distribution(const ConductorBsdf& b) { return {b.distribution, b.alpha_u, b.alpha_v}; }
Rgb fresnel(const ConductorBsdf& b, float cos_i) {
    return b.has_ior ? fresnel_conductor(cos_i, b.eta, b.k) : Rgb(1.f);
}
bool orient(const ConductorBsdf& b, Vec3& wo, Vec3& wi) {
    if (wo.z < 0 && b.two_sided) {
        wo = -wo;
        wi = -wi;
    }
    return wo.z > 0 && wi.z > 0;
}
}  // namespace

Rgb eval(const ConductorBsdf& b, const Vec3& wo_in, const Vec3& wi_in) {
    Vec3 wo = wo_in, wi = wi_in;
    if (is_smooth(b) || !orient(b, wo, wi)) return Rgb(0.f);
    Vec3 h = wo + wi;
    if (length_sq(h) == 0) return Rgb(0.f);
    h = normalize(h);
    Microfacet md = distribution(b);
    float v = md.D(h) * md.G(wo, wi, h) / (4.f * wo.z * wi.z);
    if (!std::isfinite(v) || v <= 0) return Rgb(0.f);
    return fresnel(b, dot(wi, h)) * b.specular_reflectance * v;
}

float pdf_sa(const ConductorBsdf& b, const Vec3& wo_in, const Vec3& wi_in) {
    Vec3 wo = wo_in, wi = wi_in;
    if (is_smooth(b) || !orient(b, wo, wi)) return 0.f;
    Vec3 h = wo + wi;
    if (length_sq(h) == 0) return 0.f;
    h = normalize(h);
    float d = dot(wo, h);
    if (d <= 0) return 0.f;
    // Reflection Jacobian dm/dwi = 1 / (4 |wo.m|).
    float p = distribution(b).pdf_visible_sa(wo, h) / (4.f * d);
    return std::isfinite(p) ? p : 0.f;
}

std::optional<BsdfSample> sample(const ConductorBsdf& b, const Vec3& wo_in, Vec2 u) {
    if (wo_in.z == 0 || (wo_in.z < 0 && !b.two_sided)) return std::nullopt;
    bool flip = wo_in.z < 0;
    Vec3 wo = flip ? -wo_in : wo_in;
    BsdfSample s;
    if (is_smooth(b)) {
        s.wi = reflect_local(wo_in);
        s.pdf_sa = 1.f;
        s.weight = fresnel(b, wo.z) * b.specular_reflectance;
        s.lobe = kLobeReflection | kLobeDelta;
        return s;
    }
    Microfacet md = distribution(b);
    Vec3 m = md.sample_visible(wo, u);
    Vec3 wi = reflect_dir(wo, m);
    if (wi.z <= 0) return std::nullopt;
    float d = dot(wo, m);
    if (d <= 0) return std::nullopt;
    s.pdf_sa = md.pdf_visible_sa(wo, m) / (4.f * d);
    if (!(s.pdf_sa > 0) || !std::isfinite(s.pdf_sa)) return std::nullopt;
    // f cos / pdf reduces to F G / G1(wo): avoids dividing two tiny D values.
    float g1 = md.G1(wo, m);
    if (!(g1 > 0)) return std::nullopt;
    float w = md.G(wo, wi, m) / g1;
    s.weight = fresnel(b, dot(wi, m)) * b.specular_reflectance * w;
    s.wi = flip ? -wi : wi;
    s.lobe = kLobeReflection | kLobeGlossy;
    return s;
}

}  // namespace omega
