#include "bsdf/microfacet.h"

#include <algorithm>
#include <cmath>

namespace omega {

namespace {
constexpr float kMinAlpha = 1e-4f;
constexpr double kInvSqrtPi = 0.56418958354775628695;

// Slope-space quadratic form x^2/ax^2 + y^2/ay^2 of a unit normal, divided by z^2 later.
float stretched_sq(const Vec3& m, float ax, float ay) { return sqr(m.x / ax) + sqr(m.y / ay); }

// Jakob 2014 / Mitsuba 0.6: visible slopes of the standard (alpha = 1) Beckmann distribution for a
// view at angle theta_i in the xz-plane. The x-slope CDF is inverted in the erf domain with a
// Newton step safeguarded by bisection (no discontinuities, unlike the paper's original fit).
Vec2 beckmann_sample_visible11(double cos_theta_i, Vec2 u) {
    double ux = std::clamp(double(u.x), 1e-9, 1.0 - 1e-9);
    double uy = std::clamp(double(u.y), 1e-9, 1.0 - 1e-9);
    double slope_y = erfinv(2.0 * uy - 1.0);
    if (cos_theta_i > 0.99999999) {
        // Normal incidence: the visible slope distribution is the plain 2D Gaussian.
        double r = std::sqrt(-std::log(1.0 - ux));
        double phi = 2.0 * kPiD * uy;
        return {float(r * std::cos(phi)), float(r * std::sin(phi))};
    }
    double sin_theta_i = std::sqrt(std::max(0.0, 1.0 - cos_theta_i * cos_theta_i));
    double tan_theta_i = sin_theta_i / cos_theta_i;
    double cot_theta_i = cos_theta_i / sin_theta_i;
    double theta_i = std::acos(cos_theta_i);

    double a = -1, c = std::erf(cot_theta_i);
    double fit = 1 + theta_i * (-0.876 + theta_i * (0.4265 - 0.0594 * theta_i));
    double b = c - (1 + c) * std::pow(1 - ux, fit);
    double norm = 1 / (1 + c + kInvSqrtPi * tan_theta_i * std::exp(-cot_theta_i * cot_theta_i));
    for (int it = 0; it < 60; ++it) {
        if (!(b >= a && b <= c)) b = 0.5 * (a + c);
        double x = erfinv(b);
        double value = norm * (1 + b + kInvSqrtPi * tan_theta_i * std::exp(-x * x)) - ux;
        double derivative = norm * (1 - x * tan_theta_i);
        if (std::abs(value) < 1e-12) break;
        if (value > 0) c = b;
        else a = b;
        if (c - a < 1e-15) break;
        b -= value / derivative;
    }
    return {float(erfinv(b)), float(slope_y)};
}
}  // namespace

// Giles 2010 single-precision approximation, then Newton steps against std::erf for double accuracy.
double erfinv(double y) {
    if (y <= -1) return -INFINITY;
    if (y >= 1) return INFINITY;
    double w = -std::log((1.0 - y) * (1.0 + y)), p;
    if (w < 5) {
        w -= 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        w = std::sqrt(w) - 3;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    double x = p * y;
    for (int i = 0; i < 2; ++i) {
        double d = 2.0 * kInvSqrtPi * std::exp(-x * x);
        if (!(d > 0)) break;
        x -= (std::erf(x) - y) / d;
    }
    return x;
}

Microfacet::Microfacet(MicrofacetType t, float au, float av)
    : type(t), alpha_u(std::max(au, kMinAlpha)), alpha_v(std::max(av, kMinAlpha)) {}

float Microfacet::D(const Vec3& m) const {
    if (m.z <= 0) return 0.f;
    double z2 = double(m.z) * m.z;
    double s = double(stretched_sq(m, alpha_u, alpha_v));
    double ax_ay = double(alpha_u) * alpha_v;
    double d;
    if (type == MicrofacetType::GGX) {
        double t = s + z2;  // = z^2 (1 + tan^2 (cos^2/ax^2 + sin^2/ay^2))
        d = 1.0 / (kPiD * ax_ay * t * t);
    } else {
        d = std::exp(-s / z2) / (kPiD * ax_ay * z2 * z2);
    }
    return std::isfinite(d) ? float(d) : 0.f;
}

float Microfacet::lambda(const Vec3& w) const {
    // alpha^2 tan^2(theta) along w's azimuth, from the unnormalised components.
    double z2 = double(w.z) * w.z;
    double a2t2_num = sqr(alpha_u * w.x) + sqr(alpha_v * w.y);
    if (a2t2_num == 0) return 0.f;
    if (z2 == 0) return INFINITY;
    double a2t2 = a2t2_num / z2;
    if (type == MicrofacetType::GGX) return float(0.5 * (std::sqrt(1.0 + a2t2) - 1.0));
    // Exact Beckmann Lambda: the VNDF sampler is exact, so G1 must be too for the pdf to match.
    double a = 1.0 / std::sqrt(a2t2);
    double l = 0.5 * (std::exp(-a * a) * kInvSqrtPi / a - std::erfc(a));
    return float(std::max(0.0, l));
}

float Microfacet::G1(const Vec3& w, const Vec3& m) const {
    if (dot(w, m) * w.z <= 0) return 0.f;
    float l = lambda(w);
    return std::isinf(l) ? 0.f : 1.f / (1.f + l);
}

float Microfacet::G(const Vec3& wo, const Vec3& wi, const Vec3& m) const {
    if (dot(wo, m) * wo.z <= 0 || dot(wi, m) * wi.z <= 0) return 0.f;
    float l = lambda(wo) + lambda(wi);
    return std::isinf(l) ? 0.f : 1.f / (1.f + l);
}

float Microfacet::pdf_visible_sa(const Vec3& wo, const Vec3& m) const {
    if (wo.z <= 0) return 0.f;
    float d = G1(wo, m) * std::max(0.f, dot(wo, m)) * D(m) / wo.z;
    return std::isfinite(d) ? d : 0.f;
}

Vec3 Microfacet::sample_visible(const Vec3& wo, Vec2 u) const {
    if (type == MicrofacetType::GGX) {
        // Heitz 2018, "Sampling the GGX Distribution of Visible Normals".
        Vec3 vh = normalize(Vec3(alpha_u * wo.x, alpha_v * wo.y, wo.z));
        float lensq = vh.x * vh.x + vh.y * vh.y;
        Vec3 t1 = lensq > 0 ? Vec3(-vh.y, vh.x, 0) / std::sqrt(lensq) : Vec3(1, 0, 0);
        Vec3 t2 = cross(vh, t1);
        float r = std::sqrt(u.x);
        float phi = 2.f * kPi * u.y;
        float p1 = r * std::cos(phi), p2 = r * std::sin(phi);
        float s = 0.5f * (1.f + vh.z);
        p2 = (1.f - s) * safe_sqrt(1.f - p1 * p1) + s * p2;
        Vec3 nh = t1 * p1 + t2 * p2 + vh * safe_sqrt(1.f - p1 * p1 - p2 * p2);
        Vec3 m = normalize(Vec3(alpha_u * nh.x, alpha_v * nh.y, std::max(1e-7f, nh.z)));
        return m;
    }
    // Beckmann: stretch to alpha = 1, sample slopes for the rotated view, rotate and unstretch.
    Vec3 ws = normalize(Vec3(alpha_u * wo.x, alpha_v * wo.y, wo.z));
    float sin_t = std::sqrt(ws.x * ws.x + ws.y * ws.y);
    float cos_phi = sin_t > 0 ? ws.x / sin_t : 1.f, sin_phi = sin_t > 0 ? ws.y / sin_t : 0.f;
    Vec2 s = beckmann_sample_visible11(ws.z, u);
    float sx = cos_phi * s.x - sin_phi * s.y;
    float sy = sin_phi * s.x + cos_phi * s.y;
    sx *= alpha_u;
    sy *= alpha_v;
    return normalize(Vec3(-sx, -sy, 1.f));
}

}  // namespace omega
