#pragma once
// Orthonormal frame with z as the normal. BSDFs work in this local frame.
#include "math/vec.h"

namespace omega {

struct Frame {
    Vec3 s, t, n;

    // Duff et al. 2017, "Building an Orthonormal Basis, Revisited": branchless and exact for unit n.
    static Frame from_normal(const Vec3& n) {
        float sign = std::copysign(1.f, n.z);
        float a = -1.f / (sign + n.z);
        float b = n.x * n.y * a;
        Frame f;
        f.n = n;
        f.s = {1.f + sign * n.x * n.x * a, sign * b, -sign * n.x};
        f.t = {b, sign + n.y * n.y * a, -n.y};
        return f;
    }
    Vec3 to_local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

// Spherical helpers on local directions (z up).
inline float cos_theta(const Vec3& w) { return w.z; }
inline float abs_cos_theta(const Vec3& w) { return std::abs(w.z); }
inline float cos2_theta(const Vec3& w) { return w.z * w.z; }
inline float sin2_theta(const Vec3& w) { return std::max(0.f, 1.f - w.z * w.z); }
inline float tan2_theta(const Vec3& w) { return sin2_theta(w) / cos2_theta(w); }
inline bool same_hemisphere(const Vec3& a, const Vec3& b) { return a.z * b.z > 0; }
inline Vec3 reflect_local(const Vec3& w) { return {-w.x, -w.y, w.z}; }

}  // namespace omega
