#include "math/transform.h"

#include <cmath>

namespace omega {

Mat4 Mat4::translate(const Vec3d& t) {
    Mat4 r;
    r(0, 3) = t.x; r(1, 3) = t.y; r(2, 3) = t.z;
    return r;
}

Mat4 Mat4::scale(const Vec3d& s) {
    Mat4 r;
    r(0, 0) = s.x; r(1, 1) = s.y; r(2, 2) = s.z;
    return r;
}

Mat4 Mat4::rotate(const Vec3d& axis_in, double degrees) {
    Vec3d a = normalize(axis_in);
    double th = degrees * kPiD / 180.0, s = std::sin(th), c = std::cos(th);
    Mat4 r;
    r(0, 0) = a.x * a.x + (1 - a.x * a.x) * c;
    r(0, 1) = a.x * a.y * (1 - c) - a.z * s;
    r(0, 2) = a.x * a.z * (1 - c) + a.y * s;
    r(1, 0) = a.x * a.y * (1 - c) + a.z * s;
    r(1, 1) = a.y * a.y + (1 - a.y * a.y) * c;
    r(1, 2) = a.y * a.z * (1 - c) - a.x * s;
    r(2, 0) = a.x * a.z * (1 - c) - a.y * s;
    r(2, 1) = a.y * a.z * (1 - c) + a.x * s;
    r(2, 2) = a.z * a.z + (1 - a.z * a.z) * c;
    return r;
}

Mat4 Mat4::look_at(const Vec3d& origin, const Vec3d& target, const Vec3d& up) {
    Vec3d dir = normalize(target - origin);
    Vec3d left = normalize(cross(up, dir));
    Vec3d new_up = cross(dir, left);
    Mat4 r;
    r(0, 0) = left.x; r(1, 0) = left.y; r(2, 0) = left.z;
    r(0, 1) = new_up.x; r(1, 1) = new_up.y; r(2, 1) = new_up.z;
    r(0, 2) = dir.x; r(1, 2) = dir.y; r(2, 2) = dir.z;
    r(0, 3) = origin.x; r(1, 3) = origin.y; r(2, 3) = origin.z;
    return r;
}

Mat4 Mat4::operator*(const Mat4& o) const {
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += (*this)(i, k) * o(k, j);
            r(i, j) = s;
        }
    return r;
}

Mat4 Mat4::transpose() const {
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r(i, j) = (*this)(j, i);
    return r;
}

bool Mat4::is_finite() const {
    for (double v : m)
        if (!std::isfinite(v)) return false;
    return true;
}

double Mat4::det3() const {
    const Mat4& a = *this;
    return a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1)) - a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0)) +
           a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0));
}

// Gauss-Jordan with partial pivoting; returns nullopt for singular or non-finite input.
std::optional<Mat4> Mat4::inverse() const {
    if (!is_finite()) return std::nullopt;
    double a[4][8];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            a[i][j] = (*this)(i, j);
            a[i][j + 4] = i == j ? 1.0 : 0.0;
        }
    double scale = 0;
    for (double v : m) scale = std::max(scale, std::abs(v));
    if (scale == 0) return std::nullopt;
    for (int c = 0; c < 4; ++c) {
        int piv = c;
        for (int r = c + 1; r < 4; ++r)
            if (std::abs(a[r][c]) > std::abs(a[piv][c])) piv = r;
        if (std::abs(a[piv][c]) <= 1e-300) return std::nullopt;
        if (piv != c)
            for (int j = 0; j < 8; ++j) std::swap(a[c][j], a[piv][j]);
        double inv = 1.0 / a[c][c];
        for (int j = 0; j < 8; ++j) a[c][j] *= inv;
        for (int r = 0; r < 4; ++r) {
            if (r == c) continue;
            double f = a[r][c];
            if (f == 0) continue;
            for (int j = 0; j < 8; ++j) a[r][j] -= f * a[c][j];
        }
    }
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r(i, j) = a[i][j + 4];
    if (!r.is_finite()) return std::nullopt;
    return r;
}

}  // namespace omega
