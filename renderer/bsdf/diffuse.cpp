// Lambertian and Oren-Nayar diffuse reflection.
//
// Oren-Nayar (M. Oren, S. Nayar, "Generalization of Lambert's reflectance model", SIGGRAPH 1994),
// exactly as Mitsuba 0.6 evaluates it (src/bsdfs/roughdiffuse.cpp): sigma = alpha / sqrt(2) (a
// Beckmann RMS slope turned into the V-groove slope-angle deviation; Mitsuba's fit), then
// - useFastApprox: f = rho/pi (A + B max(0, cos(phi_i - phi_o)) sin(a) tan(b)),
//   A = 1 - sigma^2 / (2 (sigma^2 + 0.33)), B = 0.45 sigma^2 / (sigma^2 + 0.09);
// - otherwise the paper's full qualitative model (its eq. 30 single scattering with the C1, C2, C3
//   terms, plus eq. 31's interreflection term rho^2 C4 (1 - cos(dphi) (2b/pi)^2)),
// with a = max(theta_i, theta_o), b = min(theta_i, theta_o). Both forms are symmetric in wi, wo
// (reciprocal), so there is no adjoint to take. Sampling is cosine-weighted (as in Mitsuba);
// pdf_sa is the cosine density in solid angle. alpha = 0 gives sigma = 0: exactly Lambert.
// Approximations: none beyond the model's own (the qualitative model is itself a fit: at rho = 1
// its albedo exceeds 1 by up to ~5% at grazing incidence, see bsdf_properties_test), except that
// the full model's rare negative values at grazing, opposite directions are clamped to 0, and
// tan((a + b) / 2) uses the cosines directly (finite where both directions graze).
#include <cmath>

#include "bsdf/models.h"
#include "sampling/warp.h"

namespace omega {

namespace {

// The Oren-Nayar factor multiplying rho / pi (the interreflection term is returned apart, as it
// multiplies rho^2 / pi). wo, wi in the upper hemisphere.
Rgb oren_nayar(const DiffuseBsdf& b, const Rgb& rho, const Vec3& wo, const Vec3& wi) {
    const float sigma = b.alpha * 0.70710678118654752f;
    const float sigma2 = sigma * sigma;
    const float sin_i = safe_sqrt(1.f - wi.z * wi.z), sin_o = safe_sqrt(1.f - wo.z * wo.z);
    float cos_dphi = 0;
    if (sin_i > 1e-4f && sin_o > 1e-4f)
        cos_dphi = std::clamp((wi.x * wo.x + wi.y * wo.y) / (sin_i * sin_o), -1.f, 1.f);
    float sin_a, sin_b, tan_b;
    if (wi.z > wo.z) {
        sin_a = sin_o;
        sin_b = sin_i;
        tan_b = sin_i / wi.z;
    } else {
        sin_a = sin_i;
        sin_b = sin_o;
        tan_b = sin_o / wo.z;
    }
    const float A = 1.f - 0.5f * sigma2 / (sigma2 + 0.33f);
    if (b.fast_approx) {
        const float B = 0.45f * sigma2 / (sigma2 + 0.09f);
        return rho * (kInvPi * (A + B * std::max(cos_dphi, 0.f) * sin_a * tan_b));
    }
    const float theta_i = std::acos(std::clamp(wi.z, -1.f, 1.f)), theta_o = std::acos(std::clamp(wo.z, -1.f, 1.f));
    const float alpha = std::max(theta_i, theta_o), beta = std::min(theta_i, theta_o);
    const float tmp = sigma2 / (sigma2 + 0.09f);
    const float tmp2 = (4.f * kInvPi * kInvPi) * alpha * beta;
    const float tmp3 = 2.f * beta * kInvPi;
    float C2 = 0.45f * tmp;
    const float C3 = 0.125f * tmp * tmp2 * tmp2;
    const float C4 = 0.17f * sigma2 / (sigma2 + 0.13f);
    C2 *= cos_dphi > 0 ? sin_a : sin_a - tmp3 * tmp3 * tmp3;
    // tan((alpha + beta) / 2) by the half-angle formula, with the cosines themselves (Mitsuba
    // recomputes them from the sines, which gives 0 / 0 when both directions graze).
    const float cos_sum = std::max(wi.z + wo.z, 1e-30f);
    const float tan_half = (sin_a + sin_b) / cos_sum;
    Rgb single = rho * (A + cos_dphi * C2 * tan_b + (1.f - std::abs(cos_dphi)) * C3 * tan_half);
    Rgb twice = rho * rho * (C4 * (1.f - cos_dphi * tmp3 * tmp3));
    // Where both directions graze on opposite sides (cos(dphi) < 0) the C2 term can take the sum
    // below zero; a BSDF cannot be negative, so it is clamped there (Mitsuba returns it as is).
    Rgb f = (single + twice) * kInvPi;
    return {std::max(f.x, 0.f), std::max(f.y, 0.f), std::max(f.z, 0.f)};
}

// Two-sided surfaces behave as if seen from wo's side (Mitsuba's twosided): flip both directions.
bool orient(const DiffuseBsdf& b, Vec3& wo, Vec3& wi) {
    if (wo.z < 0 && b.two_sided) {
        wo = -wo;
        wi = -wi;
    }
    return wo.z > 0 && wi.z > 0;
}
}  // namespace

Rgb eval(const DiffuseBsdf& b, const Vec3& wo_in, const Vec3& wi_in) {
    Vec3 wo = wo_in, wi = wi_in;
    if (!orient(b, wo, wi)) return Rgb(0.f);
    if (b.alpha > 0) return oren_nayar(b, b.reflectance, wo, wi);
    return b.reflectance * kInvPi;
}

float pdf_sa(const DiffuseBsdf& b, const Vec3& wo_in, const Vec3& wi_in) {
    Vec3 wo = wo_in, wi = wi_in;
    if (!orient(b, wo, wi)) return 0.f;
    return cosine_hemisphere_pdf_sa(wi);
}

std::optional<BsdfSample> sample(const DiffuseBsdf& b, const Vec3& wo, Vec2 u) {
    if (wo.z == 0 || (wo.z < 0 && !b.two_sided)) return std::nullopt;
    Vec3 wi = square_to_cosine_hemisphere(u);
    BsdfSample s;
    s.pdf_sa = cosine_hemisphere_pdf_sa(wi);
    if (!(s.pdf_sa > 0)) return std::nullopt;
    s.wi = wo.z < 0 ? -wi : wi;
    // f cos / pdf = pi f: (R/pi) cos / (cos/pi) = R for Lambert.
    s.weight = b.alpha > 0 ? oren_nayar(b, b.reflectance, wo.z < 0 ? -wo : wo, wi) * kPi : b.reflectance;
    s.lobe = kLobeReflection | kLobeDiffuse;
    return s;
}

}  // namespace omega
