// A sample whose value overflows is dropped whole and counted (PassReport::nonfinite), for every
// integrator: the path tracer's radiance, and the light tracer's and BDPT's splats, where the
// splats the sample already appended to its tile's list are taken back out
// (RenderSession::render_sample_index). One infinite splat left in makes its pixels infinite.
#include <gtest/gtest.h>

#include <cmath>

#include "render_harness.h"

namespace omega {
namespace {

// The metal cube scene with its light at `radiance`: near float's limit, a path's product of
// radiance, BSDF, geometry and importance overflows where its factors are large and stays finite
// elsewhere, so some samples are dropped and the rest reach the film.
SceneDesc bright_scene(float radiance, IntegratorType t) {
    SceneDesc d = test::metal_cube_scene(16, 12);
    for (ShapeDesc& s : d.shapes)
        if (s.emitter) s.emitter->radiance = Rgb(radiance);
    d.integrator.type = t;
    return d;
}

bool film_finite(const Film& f) {
    const Rect c = f.crop();
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            const PixelStats p = f.pixel(x, y);
            for (int ch = 0; ch < 3; ++ch)
                if (!std::isfinite(p.mean[ch]) || !std::isfinite(p.var_of_mean[ch])) return false;
        }
    return true;
}

TEST(NonfiniteSample, DroppedWholeAndCounted) {
    // The radiance at which each integrator's products overflow in some samples but not in most
    // (measured: 733, 285 and 285 of 1536 samples dropped; at 1e37 the splatting ones drop 8).
    const struct {
        IntegratorType type;
        const char* name;
        float radiance;
    } cases[] = {{IntegratorType::Path, "path", 3e38f}, {IntegratorType::Light, "light", 1e38f},
                 {IntegratorType::Bdpt, "bdpt", 1e38f}};
    for (const auto& c : cases) {
        auto r = test::render(bright_scene(c.radiance, c.type), 8, 3, 2);
        EXPECT_GT(r.report.nonfinite, 0u) << c.name << ": no sample overflowed, so nothing was tested";
        EXPECT_LT(r.report.nonfinite, r.report.samples / 2) << c.name;
        EXPECT_EQ(r.report.mis_errors, 0u) << c.name;
        EXPECT_TRUE(film_finite(r.film())) << c.name << ": an overflowing sample reached the film";
        EXPECT_TRUE(std::isfinite(r.report.error.image_mean)) << c.name;
        EXPECT_GT(r.report.error.image_mean, 0.0) << c.name << ": the samples that did not overflow are missing";
    }
}

}  // namespace
}  // namespace omega
