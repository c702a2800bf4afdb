#include "sampling/warp.h"

#include <algorithm>
#include <cmath>

#include "math/float_bits.h"

namespace omega {

Vec2 sincos_quarter_pi(float x) {
    // Taylor series to x^9 and x^8: the first terms left out are below 3e-9 and 3e-8 at pi/4,
    // under half an ulp of the results there. libm's sincosf reduces the argument first and was
    // a third of the cost of every diffuse bounce.
    const float x2 = x * x;
    const float s = x * (1.f + x2 * (-1.f / 6 + x2 * (1.f / 120 + x2 * (-1.f / 5040 + x2 * (1.f / 362880)))));
    const float c = 1.f + x2 * (-0.5f + x2 * (1.f / 24 + x2 * (-1.f / 720 + x2 * (1.f / 40320))));
    return {c, s};
}

namespace {

// Shirley-Chiu concentric map: low distortion, keeps stratification. Its angle is pi/4 times a
// ratio in [-1, 1], or pi/2 minus that (cos and sin swapped): always within sincos_quarter_pi.
// Which case applies is a coin flip per sample, so it is chosen by selects, not a branch: a
// mispredicted branch here cost more than the arithmetic of the map (perf, indirect-room path).
// Returns the disk point and its radius r (signed: the larger coordinate of 2u - 1).
struct DiskPoint {
    Vec2 d;
    float r;
};
inline DiskPoint concentric_map(Vec2 u) {
    float ox = 2.f * u.x - 1.f, oy = 2.f * u.y - 1.f;
    if (ox == 0 && oy == 0) return {{0, 0}, 0};
    const bool x_major = std::abs(ox) > std::abs(oy);
    const auto pick = [x_major](float a, float b) { return select_bits(x_major, a, b); };
    const float r = pick(ox, oy);
    const Vec2 cs = sincos_quarter_pi((kPi / 4.f) * (pick(oy, ox) / r));
    return {{r * pick(cs.x, cs.y), r * pick(cs.y, cs.x)}, r};
}

}  // namespace

Vec2 square_to_uniform_disk_concentric(Vec2 u) { return concentric_map(u).d; }

Vec3 square_to_cosine_hemisphere(Vec2 u) {
    const DiskPoint p = concentric_map(u);
    // The height from the radius, 1 - r^2, not from the point, 1 - |d|^2: it needs nothing from
    // the angle's division and polynomial, so the square root runs beside them instead of after
    // them, on every diffuse bounce's way to its next ray (path tracer, bench/ab_cores.sh
    // medians +1.8% and +2.9% on a VM whose noise is +-4%). Near the rim, where 1 - x cancels,
    // fewer roundings feed it.
    const float z = safe_sqrt(1.f - p.r * p.r);
    // Keep z strictly positive so the pdf never vanishes for a sampled direction.
    return {p.d.x, p.d.y, std::max(z, 1e-7f)};
}

Vec3 square_to_uniform_sphere(Vec2 u) {
    float z = 1.f - 2.f * u.x;
    float r = safe_sqrt(1.f - z * z);
    float phi = 2.f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

Vec3 square_to_uniform_hemisphere(Vec2 u) {
    float z = u.x;
    float r = safe_sqrt(1.f - z * z);
    float phi = 2.f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), std::max(z, 1e-7f)};
}

Vec3 square_to_uniform_cone(Vec2 u, float cos_max) {
    // 1 - cos computed directly keeps precision for tiny cones (distant small lights).
    float one_minus_cos_max = 1.f - cos_max;
    float one_minus_cos = u.x * one_minus_cos_max;
    float cos_t = 1.f - one_minus_cos;
    float sin_t = safe_sqrt(one_minus_cos * (2.f - one_minus_cos));
    float phi = 2.f * kPi * u.y;
    return {sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t};
}

float uniform_cone_pdf_sa(const Vec3& w, float cos_max) {
    if (w.z < cos_max) return 0.f;
    return 1.f / (2.f * kPi * (1.f - cos_max));
}

Vec2 square_to_uniform_triangle(Vec2 u) {
    float b0, b1;
    if (u.x < u.y) {
        b0 = u.x / 2.f;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.f;
        b0 = u.x - b1;
    }
    return {b0, b1};
}

float sample_tent(float u) {
    // Invert the CDF of each half.
    if (u < 0.5f) return -1.f + std::sqrt(2.f * u);
    return 1.f - std::sqrt(2.f - 2.f * u);
}

}  // namespace omega
