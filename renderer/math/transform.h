#pragma once
// Affine/projective 4x4 transforms in double precision, row-major, acting on column vectors.
// Scene loading composes these; the renderer bakes them into float geometry once.
#include <array>
#include <optional>

#include "math/vec.h"

namespace omega {

struct Mat4 {
    std::array<double, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

    double operator()(int r, int c) const { return m[size_t(r * 4 + c)]; }
    double& operator()(int r, int c) { return m[size_t(r * 4 + c)]; }

    static Mat4 identity() { return {}; }
    static Mat4 translate(const Vec3d& t);
    static Mat4 scale(const Vec3d& s);
    static Mat4 rotate(const Vec3d& axis, double degrees);
    // Mitsuba's look_at: local +z looks at target, +y is up, +x = up x dir (the image's left).
    static Mat4 look_at(const Vec3d& origin, const Vec3d& target, const Vec3d& up);

    Mat4 operator*(const Mat4& o) const;
    std::optional<Mat4> inverse() const;
    Mat4 transpose() const;
    bool is_finite() const;
    double det3() const;  // determinant of the linear part

    Vec3d point(const Vec3d& p) const;
    Vec3d vector(const Vec3d& v) const;
};

// A transform with its inverse, for normals (inverse transpose) and world-to-local queries.
struct Transform {
    Mat4 fwd, inv;
    static std::optional<Transform> make(const Mat4& m) {
        auto i = m.inverse();
        if (!i) return std::nullopt;
        return Transform{m, *i};
    }
    Vec3d point(const Vec3d& p) const { return fwd.point(p); }
    Vec3d vector(const Vec3d& v) const { return fwd.vector(v); }
    Vec3d normal(const Vec3d& n) const {
        // (M^-1)^T n
        return {inv(0, 0) * n.x + inv(1, 0) * n.y + inv(2, 0) * n.z,
                inv(0, 1) * n.x + inv(1, 1) * n.y + inv(2, 1) * n.z,
                inv(0, 2) * n.x + inv(1, 2) * n.y + inv(2, 2) * n.z};
    }
};

}  // namespace omega
