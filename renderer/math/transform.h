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

    // Inline: the sensor maps a point or direction to its local frame per light-tracing
    // connection and per MIS density, where a call cost more than the arithmetic.
    Vec3d point(const Vec3d& p) const {
        const Mat4& a = *this;
        double x = a(0, 0) * p.x + a(0, 1) * p.y + a(0, 2) * p.z + a(0, 3);
        double y = a(1, 0) * p.x + a(1, 1) * p.y + a(1, 2) * p.z + a(1, 3);
        double z = a(2, 0) * p.x + a(2, 1) * p.y + a(2, 2) * p.z + a(2, 3);
        double w = a(3, 0) * p.x + a(3, 1) * p.y + a(3, 2) * p.z + a(3, 3);
        return w == 1.0 ? Vec3d{x, y, z} : Vec3d{x / w, y / w, z / w};
    }
    Vec3d vector(const Vec3d& v) const {
        const Mat4& a = *this;
        return {a(0, 0) * v.x + a(0, 1) * v.y + a(0, 2) * v.z, a(1, 0) * v.x + a(1, 1) * v.y + a(1, 2) * v.z,
                a(2, 0) * v.x + a(2, 1) * v.y + a(2, 2) * v.z};
    }
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
