#pragma once
// Helpers shared by the stiff-and-extreme tests: scenes built in code and the statistics they
// are judged by (z-scores against the films' own variance estimates).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "render_harness.h"

namespace omega::stability {

inline double channel_mean(const PixelStats& p) { return (p.mean.x + p.mean.y + p.mean.z) / 3.0; }

// Float32 arithmetic along a path: relative slack allowed on top of the sampling error, for
// estimators whose variance is (close to) zero. Like the furnace integration test's.
constexpr double kFloatRelSlack = 2e-6;

// |mean over the crop - expected| beyond `rel_slack * expected`, in units of the standard error
// of the image mean. Zero variance with any excess gives +inf.
inline double z_with_slack(const Film& film, double expected, double rel_slack = kFloatRelSlack) {
    Rect c = film.crop();
    double diff = 0, var = 0;
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            PixelStats p = film.pixel(x, y);
            diff += channel_mean(p) - expected;
            double sd = (std::sqrt(p.var_of_mean.x) + std::sqrt(p.var_of_mean.y) + std::sqrt(p.var_of_mean.z)) / 3.0;
            var += sd * sd;
        }
    double n = double(c.area());
    double mean_diff = diff / n, se = std::sqrt(var) / n;
    double excess = std::max(0.0, std::abs(mean_diff) - rel_slack * std::abs(expected));
    return se > 0 ? excess / se : (excess > 0 ? INFINITY : 0.0);
}

// Every pixel mean is finite (the film never saw a NaN/Inf) and the session dropped none.
inline void expect_finite(const test::RenderResult& r, const std::string& what) {
    EXPECT_EQ(r.report.nonfinite, 0u) << what;
    EXPECT_EQ(r.report.mis_errors, 0u) << what;
    Rect c = r.film().crop();
    int bad = 0;
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            PixelStats p = r.film().pixel(x, y);
            if (!std::isfinite(p.mean.x + p.mean.y + p.mean.z + p.var_of_mean.x + p.var_of_mean.y + p.var_of_mean.z))
                ++bad;
        }
    EXPECT_EQ(bad, 0) << what << ": non-finite pixels";
}

// Per-pixel z-scores divide by a variance estimated from the pixel's own n samples (or batch
// means): they follow Student's t with n - 1 degrees of freedom, whose tails are heavier than the
// normal's. Bonferroni bound for n_tests such scores: the normal quantile corrected by the
// Cornish-Fisher expansion of the t quantile (Abramowitz & Stegun 26.7.5).
inline double t_threshold(int n_tests, double dof, double alpha = 1e-3) {
    double z = test::z_threshold(n_tests, alpha);
    if (!(dof > 0)) return INFINITY;
    double z3 = z * z * z, z5 = z3 * z * z;
    return z + (z3 + z) / (4 * dof) + (5 * z5 + 16 * z3 + 3 * z) / (96 * dof * dof);
}

// Smallest per-pixel sample (or batch) count over the crop, minus one.
inline double min_dof(const Film& film) {
    Rect c = film.crop();
    uint64_t n = UINT64_MAX;
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) n = std::min(n, film.pixel(x, y).n);
    return double(n) - 1.0;
}

inline const char* name_of(IntegratorType t) {
    switch (t) {
        case IntegratorType::Path: return "path";
        case IntegratorType::Light: return "light";
        case IntegratorType::Bdpt: return "bdpt";
    }
    return "?";
}

// A closed diffuse sphere of albedo rho emitting le on both sides, the camera at its centre.
inline SceneDesc sphere_furnace(float rho, float le, int w = 16) {
    SceneDesc d = test::empty_scene(w, w);
    d.integrator.max_depth = -1;
    d.materials["wall"] = test::diffuse("wall", Rgb(rho));
    ShapeDesc s;
    s.type = ShapeType::Sphere;
    s.radius = 1.0;
    s.material = "wall";
    s.emitter = EmitterDesc{Rgb(le), true};
    d.shapes.push_back(s);
    return d;
}

}  // namespace omega::stability
