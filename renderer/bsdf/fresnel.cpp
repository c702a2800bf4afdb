#include "bsdf/fresnel.h"

#include <cmath>
#include <complex>

namespace omega {

DielectricFresnel fresnel_dielectric(float cos_i, float eta) {
    DielectricFresnel out;
    bool outside = cos_i >= 0;
    out.eta_it = outside ? eta : 1.f / eta;
    out.eta_ti = outside ? 1.f / eta : eta;
    if (eta == 1.f) {
        out.r = 0;
        out.cos_t = -cos_i;
        return out;
    }
    float ci = std::min(std::abs(cos_i), 1.f);
    float sin2_t = out.eta_ti * out.eta_ti * (1.f - ci * ci);
    if (sin2_t >= 1.f) {
        out.r = 1;
        out.cos_t = 0;
        return out;
    }
    float ct = std::sqrt(1.f - sin2_t);
    float rs = (ci - out.eta_it * ct) / (ci + out.eta_it * ct);
    float rp = (out.eta_it * ci - ct) / (out.eta_it * ci + ct);
    out.r = std::min(1.f, 0.5f * (rs * rs + rp * rp));
    out.cos_t = outside ? -ct : ct;
    return out;
}

// Exact complex-IOR formula via complex arithmetic in double: the float closed forms lose
// precision near grazing incidence and for k >> eta.
float fresnel_conductor(float cos_i, float eta, float k) {
    using C = std::complex<double>;
    double ci = std::min(1.0, double(std::abs(cos_i)));
    C n(eta, k);
    double sin2_i = 1.0 - ci * ci;
    C ct = std::sqrt(C(1.0) - sin2_i / (n * n));
    C rs = (ci - n * ct) / (ci + n * ct);
    C rp = (n * ci - ct) / (n * ci + ct);
    double r = 0.5 * (std::norm(rs) + std::norm(rp));
    if (!std::isfinite(r)) return 1.f;
    return float(std::clamp(r, 0.0, 1.0));
}

Rgb fresnel_conductor(float cos_i, const Rgb& eta, const Rgb& k) {
    return {fresnel_conductor(cos_i, eta.x, k.x), fresnel_conductor(cos_i, eta.y, k.y),
            fresnel_conductor(cos_i, eta.z, k.z)};
}

}  // namespace omega
