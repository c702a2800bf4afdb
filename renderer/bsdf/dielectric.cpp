// Smooth and rough (Walter et al. 2007) dielectric interface. Notation: etap = eta_i / eta_o is the
// IOR on wi's side over the IOR on wo's side (1 for reflection). With that, the radiance BSDF obeys
// f(wo, wi) etap^2 = f(wi, wo), and the importance BSDF is f_importance(wo, wi) = f(wi, wo).
#include "bsdf/fresnel.h"
#include "bsdf/microfacet.h"
#include "bsdf/models.h"

namespace omega {

namespace {
bool is_smooth(const DielectricBsdf& b) { return b.alpha_u == 0 && b.alpha_v == 0; }
Microfacet distribution(const DielectricBsdf& b) { return {b.distribution, b.alpha_u, b.alpha_v}; }

struct RoughEval {
    Rgb f{0.f};
    float pdf_sa = 0;
};

// Evaluates f and pdf together for the generalized half vector of (wo, wi).
RoughEval eval_rough(const DielectricBsdf& b, const Vec3& wo, const Vec3& wi, TransportMode mode, bool want_f,
                     bool want_pdf) {
    RoughEval out;
    float cos_o = wo.z, cos_i = wi.z;
    if (cos_o == 0 || cos_i == 0) return out;
    bool reflect = cos_o * cos_i > 0;
    float etap = reflect ? 1.f : (cos_o > 0 ? b.eta : 1.f / b.eta);
    Vec3 m = wi * etap + wo;
    if (!(length_sq(m) > 0)) return out;
    m = normalize(m);
    if (m.z < 0) m = -m;
    float dot_o = dot(wo, m), dot_i = dot(wi, m);
    // Microfacets seen from the back by either direction contribute nothing.
    if (dot_o * cos_o <= 0 || dot_i * cos_i <= 0) return out;
    Microfacet md = distribution(b);
    // Across a refraction, evaluate Fresnel from the optically thinner side: seen from the denser
    // side, 1 - F has an infinite slope at the critical angle and float round-off is amplified.
    // Both orders of (wo, wi) then also get bit-identical F.
    float r;
    if (reflect) {
        r = fresnel_dielectric(dot_o, b.eta).r;
    } else {
        bool wo_thin = (cos_o > 0) == (b.eta >= 1.f);
        r = fresnel_dielectric(wo_thin ? dot_o : dot_i, b.eta).r;
    }
    if (reflect) {
        if (want_f) {
            float v = md.D(m) * md.G(wo, wi, m) * r / (4.f * std::abs(cos_o * cos_i));
            if (std::isfinite(v)) out.f = b.specular_reflectance * v;
        }
        if (want_pdf) {
            Vec3 wo_up = cos_o > 0 ? wo : -wo;
            out.pdf_sa = r * md.pdf_visible_sa(wo_up, m) / (4.f * std::abs(dot_o));
        }
    } else {
        float t = 1.f - r;
        float denom = sqr(dot_i + dot_o / etap);
        if (!(denom > 0)) return out;
        if (want_f) {
            float v = md.D(m) * md.G(wo, wi, m) * t * std::abs(dot_i * dot_o / (cos_i * cos_o)) / denom;
            if (mode == TransportMode::Radiance) v /= sqr(etap);
            if (std::isfinite(v)) out.f = b.specular_transmittance * v;
        }
        if (want_pdf) {
            Vec3 wo_up = cos_o > 0 ? wo : -wo;
            // Refraction Jacobian dm/dwi = |wi.m| / (wi.m + wo.m / etap)^2.
            out.pdf_sa = t * md.pdf_visible_sa(wo_up, m) * std::abs(dot_i) / denom;
        }
    }
    if (!std::isfinite(out.pdf_sa)) out.pdf_sa = 0;
    return out;
}
}  // namespace

Rgb eval(const DielectricBsdf& b, const Vec3& wo, const Vec3& wi, TransportMode mode) {
    if (is_smooth(b)) return Rgb(0.f);
    return eval_rough(b, wo, wi, mode, true, false).f;
}

float pdf_sa(const DielectricBsdf& b, const Vec3& wo, const Vec3& wi, TransportMode mode) {
    if (is_smooth(b)) return 0.f;
    return eval_rough(b, wo, wi, mode, false, true).pdf_sa;
}

std::optional<BsdfSample> sample(const DielectricBsdf& b, const Vec3& wo, float uc, Vec2 u, TransportMode mode) {
    if (wo.z == 0) return std::nullopt;
    BsdfSample s;
    if (is_smooth(b)) {
        DielectricFresnel fr = fresnel_dielectric(wo.z, b.eta);
        if (uc < fr.r) {
            s.wi = reflect_local(wo);
            s.pdf_sa = fr.r;
            s.weight = b.specular_reflectance;  // F / P(reflect)
            s.lobe = kLobeReflection | kLobeDelta;
        } else {
            s.wi = Vec3(-fr.eta_ti * wo.x, -fr.eta_ti * wo.y, fr.cos_t);
            s.pdf_sa = 1.f - fr.r;
            s.eta = fr.eta_it;
            s.weight = b.specular_transmittance;
            if (mode == TransportMode::Radiance) s.weight *= sqr(fr.eta_ti);
            s.lobe = kLobeTransmission | kLobeDelta;
        }
        if (!(s.pdf_sa > 0) || s.wi.z == 0) return std::nullopt;
        return s;
    }

    Microfacet md = distribution(b);
    Vec3 wo_up = wo.z > 0 ? wo : -wo;
    Vec3 m = md.sample_visible(wo_up, u);
    float dot_o = dot(wo, m);
    if (dot_o == 0) return std::nullopt;
    DielectricFresnel fr = fresnel_dielectric(dot_o, b.eta);
    if (uc < fr.r) {
        s.wi = reflect_dir(wo, m);
        if (s.wi.z * wo.z <= 0) return std::nullopt;
        s.lobe = kLobeReflection | kLobeGlossy;
    } else {
        s.wi = refract_dir(wo, m, dot_o, fr);
        if (s.wi.z * wo.z >= 0) return std::nullopt;
        s.eta = fr.eta_it;
        s.lobe = kLobeTransmission | kLobeGlossy;
    }
    // Re-evaluating from (wo, wi) keeps sample() exactly consistent with eval() and pdf_sa().
    RoughEval e = eval_rough(b, wo, s.wi, mode, true, true);
    if (!(e.pdf_sa > 0) || is_black(e.f)) return std::nullopt;
    s.pdf_sa = e.pdf_sa;
    s.weight = e.f * (std::abs(s.wi.z) / e.pdf_sa);
    if (!is_finite(s.weight)) return std::nullopt;
    return s;
}

}  // namespace omega
