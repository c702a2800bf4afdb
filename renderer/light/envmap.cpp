#include "light/envmap.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace omega {

namespace {

constexpr double kTwoPiSqD = 2.0 * kPiD * kPiD;  // d(omega) = 2 pi^2 sin(theta) du dv

// sin(theta) of a unit direction in the map's frame (theta measured from +y).
float sin_theta(const Vec3& l) { return std::sqrt(std::max(0.f, l.x * l.x + l.z * l.z)); }

}  // namespace

EnvMap::EnvMap(int width, int height, std::vector<Rgb> rgb, float scale, const Mat4& to_world)
    : w_(width), h_(height), texels_(std::move(rgb)) {
    if (w_ < 1 || h_ < 2) throw std::invalid_argument("an envmap needs at least 1 x 2 texels");
    if (texels_.size() != size_t(w_) * size_t(h_)) throw std::invalid_argument("envmap texel count mismatch");
    if (!std::isfinite(scale) || scale < 0) throw std::invalid_argument("envmap scale must be finite and >= 0");
    for (size_t i = 0; i < texels_.size(); ++i) {
        Rgb& c = texels_[i];
        for (int ch = 0; ch < 3; ++ch)
            if (!std::isfinite(c[ch]) || c[ch] < 0)
                throw std::invalid_argument("texel (" + std::to_string(i % size_t(w_)) + ", " +
                                            std::to_string(i / size_t(w_)) + ") has the value " + std::to_string(c[ch]) +
                                            " (radiance must be finite and >= 0)");
        c = c * scale;
    }
    // The linear part must be a rotation times a uniform scale: directions are normalised after
    // it, which is only a change of frame (no Jacobian) for such maps.
    double a[9];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) a[r * 3 + c] = to_world(r, c);
    double s2 = 0;
    for (int c = 0; c < 3; ++c) s2 += a[c] * a[c] + a[3 + c] * a[3 + c] + a[6 + c] * a[6 + c];
    s2 /= 3;
    if (!(s2 > 0) || !std::isfinite(s2)) throw std::invalid_argument("envmap to_world has no inverse");
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double d = a[i] * a[j] + a[3 + i] * a[3 + j] + a[6 + i] * a[6 + j];  // (A^T A)_ij
            if (std::abs(d - (i == j ? s2 : 0.0)) > 1e-4 * s2)
                throw std::invalid_argument("envmap to_world must be a rotation (times a uniform scale)");
        }
    const double inv_s = 1.0 / std::sqrt(s2);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            mt_[r * 3 + c] = a[r * 3 + c] * inv_s;
            m_[c * 3 + r] = a[r * 3 + c] * inv_s;  // inverse of a rotation: its transpose
        }

    // Patch (i, j) lies between texel columns i, i+1 (wrapping) and rows j, j+1.
    const int pw = w_, ph = h_ - 1;
    std::vector<double> row_w(size_t(ph), 0.0);
    std::vector<double> f(size_t(pw), 0.0);
    cols_.resize(size_t(ph));
    for (int j = 0; j < ph; ++j) {
        // Mean of sin(theta) over the patch row (exact): rows near the poles cover less sphere.
        const double st = (std::cos(kPiD * j / ph) - std::cos(kPiD * (j + 1) / ph)) / (kPiD / ph);
        for (int i = 0; i < pw; ++i) {
            const int i1 = (i + 1) % w_;
            Rgb m = (texel(i, j) + texel(i1, j) + texel(i, j + 1) + texel(i1, j + 1)) * 0.25f;
            f[size_t(i)] = double(luminance(m)) * st;
            row_w[size_t(j)] += f[size_t(i)];
            integral_ += double(average(m)) * st * (2.0 * kPiD / pw) * (kPiD / ph);
        }
        cols_[size_t(j)] = DiscreteDistribution(f);
    }
    rows_ = DiscreteDistribution(row_w);
}

Vec3 EnvMap::to_local(const Vec3& d) const {
    Vec3d v{m_[0] * d.x + m_[1] * d.y + m_[2] * d.z, m_[3] * d.x + m_[4] * d.y + m_[5] * d.z,
            m_[6] * d.x + m_[7] * d.y + m_[8] * d.z};
    return Vec3(normalize(v));
}

Vec3 EnvMap::to_world(const Vec3& l) const {
    Vec3d v{mt_[0] * l.x + mt_[1] * l.y + mt_[2] * l.z, mt_[3] * l.x + mt_[4] * l.y + mt_[5] * l.z,
            mt_[6] * l.x + mt_[7] * l.y + mt_[8] * l.z};
    return Vec3(normalize(v));
}

Vec2 EnvMap::direction_to_uv(const Vec3& l) {
    float u = std::atan2(l.x, -l.z) * kInv2Pi;
    if (u < 0) u += 1.f;
    if (!(u < 1.f)) u = 0.f;
    float v = std::acos(std::clamp(l.y, -1.f, 1.f)) * kInvPi;
    return {u, v};
}

Vec3 EnvMap::uv_to_direction(Vec2 uv) {
    double phi = 2.0 * kPiD * uv.x, theta = kPiD * uv.y;
    double st = std::sin(theta);
    return Vec3(Vec3d{st * std::sin(phi), std::cos(theta), -st * std::cos(phi)});
}

Rgb EnvMap::eval(const Vec3& d) const {
    Vec2 uv = direction_to_uv(to_local(d));
    float x = uv.x * float(w_) - 0.5f;
    float fx0 = std::floor(x);
    float fx = x - fx0;
    int x0 = int(fx0) % w_;
    if (x0 < 0) x0 += w_;
    int x1 = (x0 + 1) % w_;
    float y = uv.y * float(h_ - 1);
    int y0 = std::clamp(int(std::floor(y)), 0, h_ - 2);
    float fy = std::clamp(y - float(y0), 0.f, 1.f);
    Rgb top = texel(x0, y0) * (1 - fx) + texel(x1, y0) * fx;
    Rgb bottom = texel(x0, y0 + 1) * (1 - fx) + texel(x1, y0 + 1) * fx;
    return top * (1 - fy) + bottom * fy;
}

float EnvMap::pdf_patch_plane(Vec2 p) const {
    if (rows_.empty()) return 0.f;
    const int pw = w_, ph = h_ - 1;
    int i = std::clamp(int(p.x * float(pw)), 0, pw - 1);
    int j = std::clamp(int(p.y * float(ph)), 0, ph - 1);
    const DiscreteDistribution& c = cols_[size_t(j)];
    if (c.empty()) return 0.f;
    return rows_.pmf(size_t(j)) * c.pmf(size_t(i)) * float(pw) * float(ph);
}

float EnvMap::pdf_sa(const Vec3& d) const {
    Vec3 l = to_local(d);
    float st = sin_theta(l);
    if (!(st > 0)) return 0.f;
    Vec2 uv = direction_to_uv(l);
    float us = uv.x - 0.5f / float(w_);
    if (us < 0) us += 1.f;
    return float(double(pdf_patch_plane({us, uv.y})) / (kTwoPiSqD * st));
}

std::optional<EnvMap::Sample> EnvMap::sample(Vec2 u) const {
    if (rows_.empty()) return std::nullopt;
    float uy, ux;
    size_t j = rows_.sample(u.y, &uy);
    const DiscreteDistribution& c = cols_[j];
    if (c.empty()) return std::nullopt;
    size_t i = c.sample(u.x, &ux);
    float us = (float(i) + ux) / float(w_);
    float v = (float(j) + uy) / float(h_ - 1);
    float uu = us + 0.5f / float(w_);
    if (uu >= 1.f) uu -= 1.f;
    Sample s;
    s.d = to_world(uv_to_direction({uu, v}));
    // The density of the direction as pdf_sa() computes it, so that every strategy's MIS weight
    // uses the same number for it.
    s.pdf_sa = pdf_sa(s.d);
    if (!(s.pdf_sa > 0)) return std::nullopt;
    s.L = eval(s.d);
    return s;
}

}  // namespace omega
