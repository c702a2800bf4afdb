#include "film/filter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "math/float_bits.h"

namespace omega {

float default_filter_radius(FilterType type) {
    switch (type) {
        case FilterType::Box: return 0.5f;
        case FilterType::Tent: return 1.f;
        case FilterType::Gaussian: return 2.f;  // 4 standard deviations of 0.5
    }
    return 0.5f;
}

double erf_inv(double p) {
    if (!(p > -1.0 && p < 1.0)) {
        if (p == 1.0) return INFINITY;
        if (p == -1.0) return -INFINITY;
        return NAN;
    }
    // Giles (2010), "Approximating the erfinv function": ~1e-7 relative, a good Newton start.
    double w = -std::log((1.0 - p) * (1.0 + p));
    double x;
    if (w < 5.0) {
        w -= 2.5;
        double q = 2.81022636e-08;
        q = 3.43273939e-07 + q * w;
        q = -3.5233877e-06 + q * w;
        q = -4.39150654e-06 + q * w;
        q = 0.00021858087 + q * w;
        q = -0.00125372503 + q * w;
        q = -0.00417768164 + q * w;
        q = 0.246640727 + q * w;
        q = 1.50140941 + q * w;
        x = q * p;
    } else {
        w = std::sqrt(w) - 3.0;
        double q = -0.000200214257;
        q = 0.000100950558 + q * w;
        q = 0.00134934322 + q * w;
        q = -0.00367342844 + q * w;
        q = 0.00573950773 + q * w;
        q = -0.0076224613 + q * w;
        q = 0.00943887047 + q * w;
        q = 1.00167406 + q * w;
        q = 2.83297682 + q * w;
        x = q * p;
    }
    // Newton on erfc in the tails, where 1 - |p| is exact and erf(x) - p would lose every digit;
    // from the 1e-7 start two or three steps reach double precision (quadratic convergence); only
    // beyond float range (1 - |p| < 1e-8), where the start is poor, does it take more.
    constexpr double k2OverSqrtPi = 1.12837916709551257390;
    const bool tail = std::abs(p) > 0.5;
    const double q = 1.0 - std::abs(p);  // exact for |p| >= 0.5 (Sterbenz)
    double ax = std::abs(x);
    for (int i = 0; i < 30; ++i) {
        const double d = k2OverSqrtPi * std::exp(-ax * ax);
        if (d == 0) break;
        const double step = tail ? (std::erfc(ax) - q) / d : -(std::erf(ax) - std::abs(p)) / d;
        ax += step;
        // Quadratic convergence: the error left after a step of 1e-9 (relative) is below an ulp.
        if (std::abs(step) <= 1e-9 * ax) break;
    }
    x = std::copysign(ax, p);
    return x;
}

Filter::Filter(const FilmDesc& desc) : Filter(desc.filter, desc.filter_radius, desc.gaussian_stddev) {}

Filter::Filter(FilterType type, float radius, float gaussian_stddev) : type_(type), radius_(radius) {
    if (!(radius > 0.f) || !std::isfinite(radius))
        throw std::invalid_argument("filter radius must be positive and finite, got " + std::to_string(radius));
    if (type == FilterType::Gaussian) {
        if (!(gaussian_stddev > 0.f) || !std::isfinite(gaussian_stddev))
            throw std::invalid_argument("gaussian stddev must be positive and finite, got " +
                                        std::to_string(gaussian_stddev));
        sigma_ = gaussian_stddev;
        erf_r_ = std::erf(double(radius) / (sigma_ * std::sqrt(2.0)));
    }
}

double Filter::sample_1d(double u) const {
    const double r = radius_;
    double x = 0;
    switch (type_) {
        case FilterType::Box: x = (2.0 * u - 1.0) * r; break;
        case FilterType::Tent: x = tent_offset(float(u), radius_); break;  // sample() inlines it
        case FilterType::Gaussian:
            // Exact inverse CDF of the truncated Gaussian: one uniform per axis, weight 1, no
            // rejection, so no extra random numbers are needed.
            x = sigma_ * std::sqrt(2.0) * erf_inv(erf_r_ * (2.0 * u - 1.0));
            break;
    }
    // Rounding (and erf_r_ == 1 for very wide truncations) may step just outside the support.
    return std::clamp(x, -r, r);
}

Vec2 Filter::sample_other(Vec2 u) const {
    return {float(sample_1d(u.x)), float(sample_1d(u.y))};
}

}  // namespace omega
