#pragma once
// Pixel reconstruction filters, used only through importance sampling: a sample's film position
// is drawn from the filter's normalized density around the pixel centre, so it carries weight 1
// and the film stays a plain per-pixel sample mean (see film.h).
//
// All filters are separable: f(x, y) = f1(x) f1(y), each axis drawn from one uniform.
#include <algorithm>
#include <cmath>
#include <utility>

#include "math/float_bits.h"
#include "math/vec.h"
#include "scene/scene_desc.h"

namespace omega {

// Radius used when a scene names a filter without one. Filter(const FilmDesc&) takes
// desc.filter_radius as given (FilmDesc's default 0.5 suits only the box), so whoever fills a
// FilmDesc for a tent or Gaussian must substitute this.
float default_filter_radius(FilterType type);

class Filter {
public:
    // Throws std::invalid_argument for a non-positive or non-finite radius or stddev.
    explicit Filter(const FilmDesc& desc);
    Filter(FilterType type, float radius, float gaussian_stddev = 0.5f);

    FilterType type() const { return type_; }
    float radius() const { return radius_; }

    // Offset from the pixel centre, in pixels, in [-radius, radius]^2, distributed exactly
    // with density pdf(). Uses u.x for the x axis and u.y for the y axis, nothing else.
    // Inline, and the tent (the default filter) in float: every camera ray starts here, and the
    // call, the type switch per axis and two double square roots lay before its first ray.
    Vec2 sample(Vec2 u) const {
        if (type_ != FilterType::Tent) return sample_other(u);
        return {tent_offset(u.x, radius_), tent_offset(u.y, radius_)};
    }
    // Normalized density (integrates to 1 over the plane).
    double pdf(double x, double y) const { return pdf_1d(x) * pdf_1d(y); }
    // Inline: the splat merge and the sensor's crop coverage call it per pixel.
    double pdf_1d(double x) const {
        const double r = radius_, ax = std::abs(x);
        // A splat exactly on the border between two pixels (a focused point on a pixel corner,
        // or a position rounded onto the float grid far from the origin) is shared half and
        // half: the pixels' weights still sum to 1, and rounding to nearest moves no mass across
        // the border on average. (Giving it to both read ~2x; to one side only shifted every
        // border by half a float spacing, +0.5% at an offset of 1e5.) One branch for both
        // border cases: the merge calls this for every column and row of every splat.
        if (ax >= r) return ax > r ? 0.0 : 0.5 * pdf_1d_inside(x);
        return pdf_1d_inside(x);
    }

private:
    // The tent's inverse CDF on one axis: 2u and 2 - 2u are exact in float, as is 1 - root. The
    // half is a coin flip per sample: selects, not a branch.
    static float tent_offset(float u, float r) {
        const bool left = u < 0.5f;
        const float root = std::sqrt(select_bits(left, 2.f * u, 2.f - 2.f * u));
        return std::clamp(r * select_bits(left, root - 1.f, 1.f - root), -r, r);
    }
    Vec2 sample_other(Vec2 u) const;
    double sample_1d(double u) const;
    double pdf_1d_inside(double x) const {  // |x| <= r
        const double r = radius_;
        switch (type_) {
            case FilterType::Box: return 0.5 / r;
            case FilterType::Tent: return (r - std::abs(x)) / (r * r);
            case FilterType::Gaussian: {
                // Truncated (not shifted) Gaussian: renormalized by the mass inside the radius.
                const double z = x / sigma_;
                return std::exp(-0.5 * z * z) / (sigma_ * std::sqrt(2.0 * kPiD) * erf_r_);
            }
        }
        return 0.0;
    }

    FilterType type_;
    float radius_;
    double sigma_ = 0.5;
    // Gaussian: erf(radius / (sigma sqrt 2)), the mass inside the truncation.
    double erf_r_ = 1.0;
};

// Rounding by truncation and one compare, for values in int's range (as int(std::ceil(x)) needs
// too): without SSE4.1's roundsd, std::ceil and std::floor are library calls, four per splat
// (its merge and its bucketing).
inline int ceil_to_int(double x) {
    const int i = int(x);
    return i + (double(i) < x);
}
inline int floor_to_int(double x) {
    const int i = int(x);
    return i - (double(i) > x);
}

// The pixels [first, last] of [lo, hi) along one axis whose centre i + 0.5 lies within `radius`
// of film coordinate p: exactly those where pdf_1d(p - (i + 0.5)) can be non-zero, since the
// bounds are computed in double, where p - radius - 0.5 is exact for a float p and radius.
// (floor/ceil of the float sums, used before, took up to 4 pixels per axis where a tent of
// radius 1 reaches 2: 16 filter weights per splat for 4 non-zero ones.) first > last: none.
inline std::pair<int, int> filter_span(double p, double radius, int lo, int hi) {
    return {std::max(lo, ceil_to_int(p - radius - 0.5)), std::min(hi - 1, floor_to_int(p + radius - 0.5))};
}

// Calls fn(x, y, weight) for every pixel of `crop` whose filter footprint covers film position
// p, with the filter's density at p (how a light-tracing splat spreads over pixels).
template <class Rect, class Fn>
void for_each_filter_pixel(const Filter& filter, const Rect& crop, Vec2 p, Fn&& fn) {
    const double r = filter.radius();
    const auto [xa, xb] = filter_span(p.x, r, crop.x0, crop.x1);
    const auto [ya, yb] = filter_span(p.y, r, crop.y0, crop.y1);
    // The filter is separable (pdf = pdf_1d(x) pdf_1d(y)): one pdf_1d per column and row, the
    // same products as pdf() gives.
    constexpr int kMaxSide = 16;
    if (xb - xa >= kMaxSide) {
        for (int y = ya; y <= yb; ++y)
            for (int x = xa; x <= xb; ++x) {
                const double f = filter.pdf(double(p.x) - (x + 0.5), double(p.y) - (y + 0.5));
                if (f > 0) fn(x, y, f);
            }
        return;
    }
    double wx[kMaxSide];
    for (int x = xa; x <= xb; ++x) wx[x - xa] = filter.pdf_1d(double(p.x) - (x + 0.5));
    for (int y = ya; y <= yb; ++y) {
        const double wy = filter.pdf_1d(double(p.y) - (y + 0.5));
        if (!(wy > 0)) continue;
        for (int x = xa; x <= xb; ++x) {
            const double f = wx[x - xa] * wy;
            if (f > 0) fn(x, y, f);
        }
    }
}

// Inverse of std::erf on (-1, 1), accurate to a few ulp in double.
double erf_inv(double p);

}  // namespace omega
