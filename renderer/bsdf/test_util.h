#pragma once
// Shared helpers for the BSDF tests.
#include <cmath>
#include <string>

#include "bsdf/bsdf.h"
#include "sampling/rng.h"

namespace omega::bsdf_test {

// Direction with the given cos(theta) and azimuth phi; cos_theta may be negative (below the surface).
inline Vec3 dir(float cos_theta, float phi) {
    float s = std::sqrt(std::max(0.f, 1.f - cos_theta * cos_theta));
    return {s * std::cos(phi), s * std::sin(phi), cos_theta};
}

inline Vec2 next_2d(Rng& rng) {
    float a = rng.next_1d();
    return {a, rng.next_1d()};
}

inline Vec3 random_sphere_dir(Rng& rng) {
    float z = 1.f - 2.f * rng.next_1d();
    return dir(z, 2.f * kPi * rng.next_1d());
}

inline bool close_rel(double a, double b, double rel, double abs_tol = 1e-6) {
    return std::abs(a - b) <= rel * std::max(std::abs(a), std::abs(b)) + abs_tol;
}

}  // namespace omega::bsdf_test
