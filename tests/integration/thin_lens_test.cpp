// Also a regression test: a focused point lands exactly on a pixel corner, where a closed filter
// support gave the splat to both pixels on each axis (read about 2x the closed form).
//
// Strategy t = 0: light subpaths that hit a thin lens of finite aperture. A point light seen in a
// mirror through such a lens (L S D S D D E) can be sampled by no other strategy, so BDPT must
// reproduce the closed form with t = 0 alone; a point light seen directly (L S D D D E) is
// sampled by t = 0 and t = 1 together, which checks their MIS weights.
//
// Closed form. A point source of intensity I on the optical axis at distance D (for the mirror,
// its virtual image) lights the lens point at radius r with irradiance I cos(theta) / rho^2,
// rho^2 = D^2 + r^2, cos(theta) = D / rho. The pixel measurements sum (filters partition unity)
// to  sum_j I_j = (1 / A) int_lens E / (a cos^4 theta) dA = I / (A a D^3) (2 pi / 3) ((D^2 + R^2)^1.5 - D^3),
// with A = pi R^2 the lens area and a the area of one pixel on the image plane at z = 1.
// The totals of independent seeds are t-tested against it.
#include <gtest/gtest.h>

#include <cmath>

#include "pathspace/classify.h"
#include "render_harness.h"

namespace omega {
namespace {

constexpr int kFilmRes = 16;
constexpr double kFov = 30, kR = 0.5, kIntensity = 2.0;

double analytic_total(double D) {
    const double t = std::tan(kFov * kPiD / 360.0);
    const double a = (2 * t / kFilmRes) * (2 * t / kFilmRes);
    const double A = kPiD * kR * kR;
    return kIntensity / (A * a * D * D * D) * (2 * kPiD / 3) * (std::pow(D * D + kR * kR, 1.5) - D * D * D);
}

// Camera at the origin looking along +z with a lens of radius kR focused at `focus`; a point
// light at z_light; optionally a large perfect mirror at z = 1 facing the camera.
SceneDesc scene(double z_light, bool mirror, double focus, IntegratorType type) {
    SceneDesc d = test::empty_scene(kFilmRes, kFilmRes);
    d.integrator.type = type;
    d.integrator.max_depth = 4;
    d.sensor.type = SensorType::ThinLens;
    d.sensor.fov = float(kFov);
    d.sensor.aperture_radius = float(kR);
    d.sensor.focus_distance = float(focus);
    if (mirror) {
        d.materials["mirror"] = MaterialDesc{"mirror", ConductorBsdf{}, {}};
        ShapeDesc m;
        m.type = ShapeType::Rectangle;
        m.to_world = Mat4::translate({0, 0, 1}) * Mat4::rotate({0, 1, 0}, 180) * Mat4::scale({10, 10, 1});
        m.material = "mirror";
        d.shapes.push_back(m);
    }
    LightDesc l;
    l.type = LightType::Point;
    l.position = {0, 0, z_light};
    l.intensity = Rgb(float(kIntensity));
    d.lights.push_back(l);
    return d;
}

struct Totals {
    double mean = 0, stderr_ = 0;
    int runs = 0;
};

// Channel-averaged sum of the pixel estimates, over independent seeds.
Totals totals(const SceneDesc& d, long long spp, int runs) {
    Totals t;
    std::vector<double> v;
    for (int i = 0; i < runs; ++i) {
        auto r = test::render(d, spp, 1000 + uint64_t(i));
        EXPECT_EQ(r.report.nonfinite, 0u);
        EXPECT_EQ(r.report.mis_errors, 0u);
        double sum = 0;
        Rect c = r.film().crop();
        for (int y = c.y0; y < c.y1; ++y)
            for (int x = c.x0; x < c.x1; ++x) {
                Vec3d m = r.film().pixel(x, y).mean;
                sum += (m.x + m.y + m.z) / 3.0;
            }
        v.push_back(sum);
    }
    for (double x : v) t.mean += x / runs;
    double ss = 0;
    for (double x : v) ss += (x - t.mean) * (x - t.mean);
    t.stderr_ = std::sqrt(ss / (runs - 1) / runs);
    t.runs = runs;
    return t;
}

// Two-sided Student-t bound for 15 degrees of freedom at 1e-3 / 4 (four t-tests in this file).
constexpr int kRuns = 16;
constexpr double kTBound = 5.1;

TEST(ThinLensT0, PointLightInMirrorMatchesClosedForm) {
    // Virtual image at z = 2 - (-0.5) = 2.5; the light behind the lens is not seen directly.
    const double D = 2.5;
    auto scene_b = Scene::build(scene(-0.5, true, D, IntegratorType::Bdpt));
    EXPECT_TRUE(path_space_warnings(*scene_b, IntegratorType::Bdpt).empty());
    // bdpt reaches these paths by t = 0 (light subpaths hitting the lens) and by the planar-mirror
    // connector (the lens sampled from the light's image), weighed against each other; the
    // connector all but removes the noise, so 64 spp are plenty.
    Totals b = totals(scene(-0.5, true, D, IntegratorType::Bdpt), 64, kRuns);
    const double expected = analytic_total(D);
    double t = (b.mean - expected) / b.stderr_;
    std::printf("[ thin lens ] mirror: bdpt total %.5f +- %.5f, closed form %.5f, t %.2f\n", b.mean, b.stderr_,
                expected, t);
    EXPECT_LT(std::abs(t), kTBound);
    EXPECT_LT(b.stderr_, 0.01 * expected);  // precise enough for the sanity twin below to fail
    // Sanity twin: 5% more light is detected.
    EXPECT_GT(std::abs((b.mean - 1.05 * expected) / b.stderr_), kTBound);
    // No other strategy reaches these paths: the path and light tracers see nothing.
    auto p = test::render(scene(-0.5, true, D, IntegratorType::Path), 16, 1);
    EXPECT_EQ(p.report.error.image_mean, 0.0);
    auto l = test::render(scene(-0.5, true, D, IntegratorType::Light), 16, 1);
    EXPECT_EQ(l.report.error.image_mean, 0.0);
}

TEST(ThinLensT0, PointLightSeenDirectlyAgreesAcrossStrategies) {
    // Out of focus: the light at 2.5, the lens focused at 1.5 spreads it over a disk of pixels.
    const double D = 2.5;
    const double expected = analytic_total(D);
    for (IntegratorType type : {IntegratorType::Bdpt, IntegratorType::Light}) {
        Totals r = totals(scene(D, false, 1.5, type), 128, kRuns);
        double t = (r.mean - expected) / r.stderr_;
        std::printf("[ thin lens ] direct, %s: total %.5f +- %.5f, closed form %.5f, t %.2f\n",
                    type == IntegratorType::Bdpt ? "bdpt" : "light", r.mean, r.stderr_, expected, t);
        EXPECT_LT(std::abs(t), kTBound);
        EXPECT_LT(r.stderr_, 0.01 * expected);
    }
}

// The t = 0 strategy layer carries the mirror image alone; its unweighted image equals the
// whole (weight 1) and the k = 2 layers of every other strategy are empty.
TEST(ThinLensT0, StrategyImagesShowT0) {
    SceneDesc d = scene(-0.5, true, 2.5, IntegratorType::Bdpt);
    d.integrator.mirror_connector = false;  // else it shares the image, and it has no strategy layer
    RenderSettings settings;
    settings.integrator = d.integrator;
    settings.halt.spp = 64;
    settings.strategy_images_max_k = 2;
    auto sc = Scene::build(d);
    RenderSession session(*sc, settings);
    session.run();
    const StrategyImages* si = session.strategy_images();
    ASSERT_NE(si, nullptr);
    const long long spp = 64;
    double t0 = si->image_mean(3, 0, true, spp);  // k = 2: light, mirror, lens
    EXPECT_GT(t0, 0.0);
    EXPECT_NEAR(si->image_mean(3, 0, false, spp), t0, 1e-12 + 1e-9 * t0);
    EXPECT_NEAR(session.film().estimate_error().image_mean, t0, 1e-6 * t0);
    for (int s = 0; s <= 2; ++s) EXPECT_EQ(si->image_mean(s, 3 - s, false, spp), 0.0) << "s=" << s;
}

}  // namespace
}  // namespace omega
