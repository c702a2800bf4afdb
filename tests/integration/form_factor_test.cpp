// A diffuse plane lit by a parallel rectangular area light: the outgoing radiance is
// rho * Le * F(x), with F the analytic point-to-rectangle form factor. Direct light only.
#include <gtest/gtest.h>

#include <cmath>

#include "analytic.h"
#include "render_harness.h"

namespace omega {
namespace {

struct FfSetup {
    double lx0 = 0.5, lx1 = 1.5, ly0 = -0.5, ly1 = 0.5, h = 1.0;  // the light
    double cx = -0.5, cy = 0.0, half = 0.75;                       // the viewed square
    float rho = 0.8f, le = 4.f;
    int res = 24;
};

SceneDesc make_scene(const FfSetup& s, FilterType filter) {
    SceneDesc d = test::empty_scene(s.res, s.res);
    d.integrator.max_depth = 2;
    d.sensor.type = SensorType::Orthographic;
    d.sensor.film.filter = filter;
    d.sensor.to_world = Mat4::look_at({s.cx, s.cy, 5}, {s.cx, s.cy, 0}, {0, 1, 0}) * Mat4::scale({s.half, s.half, 1});
    d.materials["floor"] = test::diffuse("floor", Rgb(s.rho));
    d.materials["black"] = MaterialDesc{"black", BlackBsdf{}, {}};
    ShapeDesc floor;
    floor.type = ShapeType::Rectangle;
    floor.to_world = Mat4::scale({10, 10, 1});
    floor.material = "floor";
    d.shapes.push_back(floor);
    ShapeDesc light;
    light.type = ShapeType::Rectangle;
    // Rectangle [-1,1]^2 facing +z -> flipped to face down, sized and placed over the light area.
    light.to_world = Mat4::translate({0.5 * (s.lx0 + s.lx1), 0.5 * (s.ly0 + s.ly1), s.h}) *
                     Mat4::scale({0.5 * (s.lx1 - s.lx0), 0.5 * (s.ly1 - s.ly0), 1}) * Mat4::rotate({1, 0, 0}, 180);
    light.material = "black";
    light.emitter = EmitterDesc{Rgb(s.le), false};
    d.shapes.push_back(light);
    return d;
}

// Expected pixel value: the box-filtered radiance rho * Le * F over the pixel.
double expected_pixel(const FfSetup& s, int x, int y) {
    return test::pixel_average(x, y, s.res, s.cx, s.cy, s.half, [&](double wx, double wy) {
        return double(s.rho) * s.le * test::rect_form_factor(wx, wy, s.lx0, s.lx1, s.ly0, s.ly1, s.h);
    });
}

TEST(FormFactor, PlaneUnderRectangularLight) {
    FfSetup s;
    auto r = test::render(make_scene(s, FilterType::Box), 64, 7);
    auto z = test::z_against(r.film(), [&](int x, int y) { return expected_pixel(s, x, y); });
    double bound = test::z_threshold(1);
    EXPECT_LT(std::abs(z.z), bound) << "aggregate z " << z.z;
    // Per pixel, with a Bonferroni bound over all pixels: catches a wrong falloff shape.
    EXPECT_LT(z.max_abs_z, test::z_threshold(s.res * s.res)) << "worst pixel z";
    EXPECT_EQ(r.report.nonfinite, 0u);
}

TEST(FormFactor, DetectsAWrongAnswer) {
    FfSetup s;
    auto r = test::render(make_scene(s, FilterType::Box), 64, 8);
    auto z = test::z_against(r.film(), [&](int x, int y) { return 1.03 * expected_pixel(s, x, y); });
    EXPECT_GT(std::abs(z.z), test::z_threshold(1));
}

}  // namespace
}  // namespace omega

namespace omega {
namespace {

// flip_normals turns a one-sided emitter around: a rectangle facing up, flipped, must light the
// floor exactly like the rotated one above (and a double flip would leave the floor dark).
TEST(FormFactor, FlipNormalsTurnsTheEmitterAround) {
    FfSetup s;
    SceneDesc d = make_scene(s, FilterType::Box);
    ShapeDesc& light = d.shapes[1];
    light.to_world = Mat4::translate({0.5 * (s.lx0 + s.lx1), 0.5 * (s.ly0 + s.ly1), s.h}) *
                     Mat4::scale({0.5 * (s.lx1 - s.lx0), 0.5 * (s.ly1 - s.ly0), 1});
    light.flip_normals = true;
    auto r = test::render(d, 64, 9);
    auto z = test::z_against(r.film(), [&](int x, int y) { return expected_pixel(s, x, y); });
    EXPECT_LT(std::abs(z.z), test::z_threshold(1)) << "aggregate z " << z.z;
    EXPECT_GT(r.report.error.image_mean, 0.0);
}

}  // namespace
}  // namespace omega

namespace omega {
namespace {

// The breakdown's `L D E` (App. 8.A) is exactly the direct part: with unbounded depth it matches
// the closed form rho Le F of the whole image and of a pixel box, and carries all of it (nothing
// else reaches the camera: the floor cannot see itself).
TEST(FormFactor, BreakdownDirectClassIsTheClosedForm) {
    FfSetup s;
    s.res = 12;
    SceneDesc d = make_scene(s, FilterType::Box);
    d.integrator.max_depth = -1;
    const Rect box{2, 3, 7, 9};
    for (IntegratorType type : {IntegratorType::Path, IntegratorType::Bdpt}) {
        d.integrator.type = type;
        for (bool use_box : {false, true}) {
            BreakdownDesc bd;
            if (use_box) bd.box = box;
            const Rect region = use_box ? box : Rect{0, 0, s.res, s.res};
            double expected = 0;
            for (int y = region.y0; y < region.y1; ++y)
                for (int x = region.x0; x < region.x1; ++x) expected += expected_pixel(s, x, y);
            expected /= double(region.area());
            auto r = test::render_breakdown(d, 256, bd, 21, 2);
            const BreakdownReport rep = test::breakdown(r);
            const BreakdownRow* lde = test::breakdown_row(rep, "class", "L D E");
            ASSERT_NE(lde, nullptr);
            EXPECT_LT(std::abs(lde->mu - expected) / lde->mu_stderr, test::z_threshold(4))
                << integrator_name(type) << " box " << use_box << " mu " << lde->mu << " +- " << lde->mu_stderr
                << " expected " << expected;
            EXPECT_NEAR(lde->fraction, 1.0, 1e-12);
            // The test can fail: 5% off is rejected.
            EXPECT_GT(std::abs(lde->mu - 1.05 * expected) / lde->mu_stderr, test::z_threshold(1));
        }
    }
}

}  // namespace
}  // namespace omega
