// Plastic and rough plastic: a dielectric coat (relative index eta) over a Lambertian substrate.
//
// The model is Tungsten's (Plastic.cpp and RoughPlastic.cpp, commit 88ea020), because the
// reference renders we are judged against (Bitterli's scenes, ../shared/scenes/materials) were made
// with Tungsten. With F(mu) the unpolarised dielectric Fresnel reflectance seen from outside,
// mu_o = wo.z, mu_i = wi.z, rho the diffuse reflectance:
//
//   smooth:  f = F(mu_o) Ks delta_mirror + S(wo, wi)
//   rough:   f = Ks F(wi.m) D(m) G(wo, wi, m) / (4 mu_o mu_i)  (m the half vector)  + S(wo, wi)
//   S(wo, wi) = (1 - F(mu_o)) (1 - F(mu_i)) / eta^2 · rho_eff / pi
//   rho_eff  = rho / (1 - rho Fdr_int)   (nonlinear: Tungsten, Mitsuba's nonlinear = true)
//            = rho / (1 - Fdr_int)       (Mitsuba's default nonlinear = false)
//
// Fdr_int = 2 ∫ F_int(mu) mu dmu is the hemispherical internal reflectance (Tungsten's
// computeDiffuseFresnel, 0.596 for eta 1.5). The substrate term sums the light bouncing between
// substrate and coat: each bounce the diffuse radiance meets the coat and Fdr_int of it returns.
// Its normalisation is exact: with rho = 1 the smooth plastic's albedo is 1 at every angle, since
// 1 - Fdr_ext = eta^2 (1 - Fdr_int) (a test checks this; it is how Fdr_int's quadrature is
// verified). Ks (specular_reflectance) is Mitsuba's, absent in Tungsten (= 1 there).
//
// Choices and approximations, each deliberate:
// - Rough plastic's substrate uses the SMOOTH coat's Fresnel (1 - F(mu_o))(1 - F(mu_i)) and the
//   smooth Fdr_int, as Tungsten does. Mitsuba instead uses the rough interface's transmittance
//   (precomputed tables) and the rough internal reflectance; the two differ more as alpha grows
//   (README of ../shared/scenes/materials, "roughplastic substrate term"). Tungsten's form keeps the
//   BSDF reciprocal and needs no tables. It is not exactly energy conserving: the glossy lobe's
//   microfacet Fresnel is not what the substrate is weighted with, so the albedo can exceed 1 by a
//   fraction of a percent near normal incidence for rho = 1 (bounded by a test).
// - Fdr_int by quadrature in double (Tungsten: 10^6-point trapezoid; Mitsuba: a fitted polynomial,
//   about 0.1% off), once per material in set_eta().
// - No absorbing coat (Tungsten's thickness / sigma_a): Mitsuba has no such parameter, so the
//   average transmittance in Tungsten's lobe selection is 1.
// - Lobe selection (Tungsten): the coat's reflection is chosen with probability
//   P_s = w_s / (w_s + w_d), w_s = F(mu_o) mean(Ks), w_d = 1 - F(mu_o) (Tungsten: w_s = F(mu_o),
//   the same for Ks = 1), independent of rho so that no density depends on a texture. The
//   substrate is sampled by cosine-weighted directions, the rough coat by visible normals (Tungsten
//   samples D with a widened alpha: a different density, the same expectation). pdf_sa of the
//   rough plastic is the mixture P_s p_coat + (1 - P_s) p_cos, which sample() reports whatever lobe
//   it drew (one-sample MIS over the lobes, as Tungsten does). For the smooth coat the mirror lobe
//   has probability P_s (a discrete probability, not a density) and pdf_sa = (1 - P_s) p_cos.
// - Reciprocity: f(wo, wi) = f(wi, wo) for every term (the 1/eta^2 is already symmetric: the
//   substrate's radiance is scaled into and back out of the coat), so the adjoint BSDF used by
//   light tracing and BDPT is the same function and TransportMode is not needed.
// - One-sided like Mitsuba unless two_sided (then the back sees the same coat, as Tungsten's
//   two-sided shading does).
#include <cmath>

#include "bsdf/fresnel.h"
#include "bsdf/microfacet.h"
#include "bsdf/models.h"
#include "sampling/warp.h"

namespace omega {

namespace {

// Unpolarised Fresnel reflectance in double for light inside the coat (index eta against 1)
// meeting it at cosine mu.
double fresnel_internal(double mu, double eta) {
    double sin2_t = eta * eta * (1.0 - mu * mu);
    if (sin2_t >= 1.0) return 1.0;
    double ct = std::sqrt(1.0 - sin2_t);
    double rs = (eta * mu - ct) / (eta * mu + ct), rp = (mu - eta * ct) / (mu + eta * ct);
    return 0.5 * (rs * rs + rp * rp);
}

bool is_smooth(const PlasticBsdf& b) { return b.alpha == 0; }

bool orient(const PlasticBsdf& b, Vec3& wo, Vec3& wi) {
    if (wo.z < 0 && b.two_sided) {
        wo = -wo;
        wi = -wi;
    }
    return wo.z > 0 && wi.z > 0;
}

float fresnel_outside(const PlasticBsdf& b, float mu) { return fresnel_dielectric(mu, b.eta).r; }

float specular_probability(const PlasticBsdf& b, float f_o) {
    float ks = (b.specular_reflectance.x + b.specular_reflectance.y + b.specular_reflectance.z) / 3.f;
    float ws = f_o * ks, wd = 1.f - f_o;
    return ws + wd > 0 ? ws / (ws + wd) : 0.f;
}

Rgb substrate(const PlasticBsdf& b, float f_o, float f_i) {
    const Rgb& rho = b.diffuse_reflectance;
    Rgb rho_eff = b.nonlinear ? rho / (Rgb(1.f) - rho * b.fdr_int) : rho / (1.f - b.fdr_int);
    return rho_eff * ((1.f - f_o) * (1.f - f_i) / (b.eta * b.eta) * kInvPi);
}

Microfacet coat(const PlasticBsdf& b) { return {b.distribution, b.alpha, b.alpha}; }

// Coat lobe of the rough plastic, f and its sampling density (solid angle), for wo, wi above.
struct CoatEval {
    Rgb f{0.f};
    float pdf_sa = 0;
};
CoatEval eval_coat(const PlasticBsdf& b, const Vec3& wo, const Vec3& wi) {
    CoatEval out;
    Vec3 h = wo + wi;
    if (!(length_sq(h) > 0)) return out;
    h = normalize(h);
    float d = dot(wo, h);
    if (d <= 0) return out;
    Microfacet md = coat(b);
    float v = md.D(h) * md.G(wo, wi, h) / (4.f * wo.z * wi.z);
    if (std::isfinite(v) && v > 0) out.f = b.specular_reflectance * (fresnel_outside(b, dot(wi, h)) * v);
    // Reflection Jacobian dm/dwi = 1 / (4 |wo.m|).
    float p = md.pdf_visible_sa(wo, h) / (4.f * d);
    out.pdf_sa = std::isfinite(p) ? p : 0.f;
    return out;
}

}  // namespace

float plastic_fdr_int(float eta_f) {
    const double eta = eta_f;
    // Over x = mu^2 (dx = 2 mu dmu). Below the critical x_c total internal reflection gives F = 1;
    // above it F has a square-root edge at x_c, which the substitution x = x_c + (1 - x_c) t^2
    // turns into a smooth integrand, so composite Simpson converges fast.
    const double xc = eta > 1.0 ? 1.0 - 1.0 / (eta * eta) : 0.0;
    const int n = 4096;
    double sum = 0;
    for (int i = 0; i <= n; ++i) {
        double t = double(i) / n;
        double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        double x = xc + (1.0 - xc) * t * t;
        sum += w * fresnel_internal(std::sqrt(x), eta) * 2.0 * (1.0 - xc) * t;
    }
    return float(xc + sum / (3.0 * n));
}

void PlasticBsdf::set_eta(float e) {
    eta = e;
    fdr_int = plastic_fdr_int(e);
}

Rgb eval(const PlasticBsdf& b, const Vec3& wo_in, const Vec3& wi_in) {
    Vec3 wo = wo_in, wi = wi_in;
    if (!orient(b, wo, wi)) return Rgb(0.f);
    Rgb f = substrate(b, fresnel_outside(b, wo.z), fresnel_outside(b, wi.z));
    if (!is_smooth(b)) f += eval_coat(b, wo, wi).f;
    return f;
}

float pdf_sa(const PlasticBsdf& b, const Vec3& wo_in, const Vec3& wi_in) {
    Vec3 wo = wo_in, wi = wi_in;
    if (!orient(b, wo, wi)) return 0.f;
    float ps = specular_probability(b, fresnel_outside(b, wo.z));
    float p = (1.f - ps) * cosine_hemisphere_pdf_sa(wi);
    if (!is_smooth(b)) p += ps * eval_coat(b, wo, wi).pdf_sa;
    return p;
}

std::optional<BsdfSample> sample(const PlasticBsdf& b, const Vec3& wo_in, float uc, Vec2 u) {
    if (wo_in.z == 0 || (wo_in.z < 0 && !b.two_sided)) return std::nullopt;
    const bool flip = wo_in.z < 0;
    const Vec3 wo = flip ? -wo_in : wo_in;
    const float f_o = fresnel_outside(b, wo.z);
    const float ps = specular_probability(b, f_o);
    BsdfSample s;
    Vec3 wi;
    if (uc < ps) {
        if (is_smooth(b)) {
            s.wi = reflect_local(wo_in);
            s.pdf_sa = ps;
            s.weight = b.specular_reflectance * (f_o / ps);
            s.lobe = kLobeReflection | kLobeDelta;
            return s;
        }
        wi = reflect_dir(wo, coat(b).sample_visible(wo, u));
        s.lobe = kLobeReflection | kLobeGlossy;
    } else {
        wi = square_to_cosine_hemisphere(u);
        s.lobe = kLobeReflection | kLobeDiffuse;
    }
    if (wi.z <= 0) return std::nullopt;
    // eval() and pdf_sa() of the whole BSDF, so that the weight is exactly f cos / pdf_sa whichever
    // lobe drew the direction.
    s.pdf_sa = pdf_sa(b, wo, wi);
    if (!(s.pdf_sa > 0) || !std::isfinite(s.pdf_sa)) return std::nullopt;
    s.weight = eval(b, wo, wi) * (wi.z / s.pdf_sa);
    if (!is_finite(s.weight)) return std::nullopt;
    s.wi = flip ? -wi : wi;
    return s;
}

}  // namespace omega
