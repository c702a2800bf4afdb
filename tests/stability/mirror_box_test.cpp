// A closed box of mirrors, emitting Le on both sides, the camera inside: every vertex of a path
// is hit emission, so a path of k edges returns Le * k.
// - Perfect mirrors (R = 1) and max_depth 1000: exactly 1000 Le per sample (zero variance).
// - R = 0.999, unbounded depth (about 1000 bounces per path): Le / (1 - R), by a z-test.
// - Perfect mirrors and unbounded depth: nothing ever absorbs, and roulette (survival = throughput
//   = 1) never ends a path; the hard cap of kMaxUnboundedDepth edges does: Le * 65536 exactly.
//   (The path tracer had no such cap and never returned here; see path_tracer.h.)
#include <gtest/gtest.h>

#include <cmath>

#include "stability_util.h"

namespace omega {
namespace {

SceneDesc mirror_box(float reflectance, int max_depth, IntegratorType type, int res) {
    SceneDesc d = test::empty_scene(res, res);
    d.integrator.type = type;
    d.integrator.max_depth = max_depth;
    d.sensor.to_world = Mat4::translate({0.13, -0.21, 0.07}) * Mat4::rotate({1, 2, 3}, 17);
    d.sensor.fov = 90;
    ConductorBsdf mirror;
    mirror.specular_reflectance = Rgb(reflectance);
    d.materials["mirror"] = MaterialDesc{"mirror", mirror, {}};
    ShapeDesc box;
    box.type = ShapeType::Cube;
    box.to_world = Mat4::rotate({0, 1, 1}, 23) * Mat4::scale({1, 0.7, 1.3});
    box.material = "mirror";
    box.emitter = EmitterDesc{Rgb(1.f), true};
    d.shapes.push_back(box);
    return d;
}

// The path tracer's estimate is exact (integers in float); BDPT splits the directly seen emitter
// (k = 1) between s = 0 and light tracing (s = 1, t = 1), whose splats land anywhere: the
// image mean is then tested against 1000 by its noise.
TEST(MirrorBox, ThousandBouncesExactly) {
    for (IntegratorType t : {IntegratorType::Path, IntegratorType::Bdpt}) {
        auto r = test::render(mirror_box(1.f, 1000, t, t == IntegratorType::Path ? 8 : 4), t == IntegratorType::Path ? 2 : 16, 81);
        stability::expect_finite(r, "mirror box 1000");
        Rect c = r.film().crop();
        int wrong = 0;
        for (int y = c.y0; y < c.y1; ++y)
            for (int x = c.x0; x < c.x1; ++x)
                if (stability::channel_mean(r.film().pixel(x, y)) != 1000.0) ++wrong;
        if (t == IntegratorType::Path) EXPECT_EQ(wrong, 0) << "mean " << r.report.error.image_mean;
        else EXPECT_LT(stability::z_with_slack(r.film(), 1000.0), test::z_threshold(2)) << "bdpt mean " << r.report.error.image_mean;
        std::printf("[ stability ] %s mirror box, R=1, max_depth 1000: mean %.9g (expected 1000), %.3g rays, %.2f s\n",
                    stability::name_of(t), r.report.error.image_mean, double(r.report.rays), r.report.elapsed_s);
    }
}

TEST(MirrorBox, LossyMirrorsMatchGeometricSeries) {
    const float R = 0.999f;
    auto r = test::render(mirror_box(R, -1, IntegratorType::Path, 8), 32, 82);
    stability::expect_finite(r, "mirror box 0.999");
    const double expected = 1.0 / (1.0 - double(R));
    // Float accumulation over ~1000 terms: a relative slack of 1e-4 is still far below the noise.
    double z = stability::z_with_slack(r.film(), expected, 1e-4);
    EXPECT_LT(z, test::z_threshold(1)) << "mean " << r.report.error.image_mean << " expected " << expected;
    std::printf("[ stability ] path mirror box, R=0.999, unbounded: mean %.6g +- %.2g (expected %.6g), z %.2f, "
                "%.3g rays, %.2f s\n",
                r.report.error.image_mean, r.report.error.image_mean_stderr, expected, z, double(r.report.rays),
                r.report.elapsed_s);
}

TEST(MirrorBox, PerfectMirrorsUnboundedStopAtTheCap) {
    auto r = test::render(mirror_box(1.f, -1, IntegratorType::Path, 4), 1, 83);
    stability::expect_finite(r, "mirror box cap");
    EXPECT_EQ(r.report.error.image_mean, double(kMaxUnboundedDepth));
    std::printf("[ stability ] path mirror box, R=1, unbounded: mean %.9g (cap %d), %.3g rays, %.2f s\n",
                r.report.error.image_mean, kMaxUnboundedDepth, double(r.report.rays), r.report.elapsed_s);
}

TEST(MirrorBoxSanity, DetectsAWrongReflectance) {
    auto r = test::render(mirror_box(0.998f, -1, IntegratorType::Path, 8), 32, 84);
    EXPECT_GT(stability::z_with_slack(r.film(), 1.0 / (1.0 - 0.999), 1e-4), test::z_threshold(1));
}

}  // namespace
}  // namespace omega
