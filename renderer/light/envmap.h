#pragma once
// An equirectangular (latitude-longitude) environment map, Mitsuba 3's `envmap`.
//
// Lookup (Mitsuba 3, src/emitters/envmap.cpp): a world direction d is taken to the map's frame by
// to_world^-1, then u = atan2(d.x, -d.z) / 2pi (wrapping), v = acos(d.y) / pi, and the radiance is
// the bilinear interpolation of the texels at x = u W - 1/2 (texel-centred, wrapping in x) and
// y = v (H - 1) (rows at the corners: row 0 is the direction +y, row H-1 is -y), times `scale`.
//
// Sampling (pbrt-v4's ImageInfiniteLight, Mitsuba 3's envmap): a piecewise-constant 2D
// distribution over the W x (H - 1) bilinear patches of the map, each weighted by the exact mean
// of its bilinear luminance (the mean of its four corners) times sin(theta) at its centre: a
// patch has density > 0 exactly where its radiance can be > 0, so the support is covered. Within
// a patch the density is uniform in (u, v); the solid-angle density is p(u, v) / (2 pi^2 sin theta).
// Approximation: none in the radiance; the sampling density only approximates L sin(theta)
// (that costs variance, not bias).
#include <algorithm>
#include <memory>
#include <optional>
#include <vector>

#include "math/transform.h"
#include "math/vec.h"
#include "sampling/distribution.h"

namespace omega {

class EnvMap {
public:
    // `rgb` holds width x height texels, the top row (+y) first. Throws std::invalid_argument for
    // a map under 1 x 2 texels, a non-finite or negative texel, or a to_world without an inverse.
    EnvMap(int width, int height, std::vector<Rgb> rgb, float scale, const Mat4& to_world);

    // Radiance arriving from world direction d (unit; d points away from the scene).
    Rgb eval(const Vec3& d) const;
    // A direction d (away from the scene) with its density per unit solid angle; nullopt where
    // the map is black.
    struct Sample {
        Vec3 d;
        Rgb L;
        float pdf_sa = 0;
    };
    std::optional<Sample> sample(Vec2 u) const;
    // Density per unit solid angle with which sample() returns d.
    float pdf_sa(const Vec3& d) const;
    // Integral of the channel average of the radiance over the sphere, W/(m^2) per unit
    // projected area: the power through a disk of radius r is pi r^2 times this.
    double integral() const { return integral_; }
    bool black() const { return !(integral_ > 0); }

    // Map coordinates of a direction in the map's frame, and back (exposed for tests).
    static Vec2 direction_to_uv(const Vec3& local);
    static Vec3 uv_to_direction(Vec2 uv);
    // Density in the patch plane (u', v) in [0,1)^2, u' = u - 1/(2W) wrapped, per unit area.
    float pdf_patch_plane(Vec2 uv_shifted) const;
    Vec3 to_local(const Vec3& d) const;
    Vec3 to_world(const Vec3& local) const;
    int width() const { return w_; }
    int height() const { return h_; }

private:
    const Rgb& texel(int x, int y) const { return texels_[size_t(y) * size_t(w_) + size_t(x)]; }
    int w_ = 0, h_ = 0;
    std::vector<Rgb> texels_;  // already multiplied by scale
    double m_[9] = {};         // world -> local linear part (rows), normalised directions
    double mt_[9] = {};        // local -> world linear part
    DiscreteDistribution rows_;               // over the H - 1 patch rows
    std::vector<DiscreteDistribution> cols_;  // per patch row, over its W patches
    double integral_ = 0;
};

}  // namespace omega
