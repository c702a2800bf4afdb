// The same scene at scale 1e-4, 1, 1e4 and 1e6, and 1e5 away from the origin, renders the same
// image: z-tested per pixel against the closed form of a diffuse plane under a parallel
// rectangular light (rho Le F(x), F the point-to-rectangle form factor), which no scaling or
// translation changes. Self-intersection or leaks at extreme scales would bias whole regions.
#include <gtest/gtest.h>

#include <cmath>

#include "analytic.h"
#include "stability_util.h"

namespace omega {
namespace {


struct FfSetup {
    double lx0 = 0.5, lx1 = 1.5, ly0 = -0.5, ly1 = 0.5, h = 1.0;  // the light, facing down
    double cx = -0.25, cy = 0.0, half = 1.0;                      // viewed square (the light's edge crosses it)
    float rho = 0.8f, le = 4.f;
    int res = 16;
};

// Everything (camera included) mapped by translate(offset) * scale(s).
SceneDesc scene(const FfSetup& st, double s, const Vec3d& offset, IntegratorType type) {
    Mat4 T = Mat4::translate(offset) * Mat4::scale({s, s, s});
    SceneDesc d = test::empty_scene(st.res, st.res);
    d.integrator.type = type;
    d.integrator.max_depth = -1;
    d.sensor.type = SensorType::Orthographic;
    d.sensor.to_world = T * Mat4::look_at({st.cx, st.cy, 0.4}, {st.cx, st.cy, 0}, {0, 1, 0}) *
                        Mat4::scale({st.half, st.half, 1});
    d.materials["floor"] = test::diffuse("floor", Rgb(st.rho));
    d.materials["black"] = MaterialDesc{"black", BlackBsdf{}, {}};
    ShapeDesc floor;
    floor.type = ShapeType::Rectangle;
    floor.to_world = T * Mat4::scale({10, 10, 1});
    floor.material = "floor";
    d.shapes.push_back(floor);
    ShapeDesc light;
    light.type = ShapeType::Rectangle;
    light.to_world = T * Mat4::translate({0.5 * (st.lx0 + st.lx1), 0.5 * (st.ly0 + st.ly1), st.h}) *
                     Mat4::scale({0.5 * (st.lx1 - st.lx0), 0.5 * (st.ly1 - st.ly0), 1}) * Mat4::rotate({1, 0, 0}, 180);
    light.material = "black";
    light.emitter = EmitterDesc{Rgb(st.le), false};
    d.shapes.push_back(light);
    return d;
}

double expected_pixel(const FfSetup& s, int x, int y) {
    return test::pixel_average(x, y, s.res, s.cx, s.cy, s.half, [&](double wx, double wy) {
        return double(s.rho) * s.le * test::rect_form_factor(wx, wy, s.lx0, s.lx1, s.ly0, s.ly1, s.h);
    });
}

struct Placement {
    double scale;
    Vec3d offset;
    const char* label;
};
const Placement kPlacements[] = {{1e-4, {0, 0, 0}, "scale 1e-4"}, {1.0, {0, 0, 0}, "scale 1"},
                                 {1e4, {0, 0, 0}, "scale 1e4"},   {1e6, {0, 0, 0}, "scale 1e6"},
                                 {1.0, {1e5, -1e5, 1e5}, "offset 1e5"}};
constexpr int kTests = 5 * 2;

class ScaleOffset : public ::testing::TestWithParam<IntegratorType> {};

TEST_P(ScaleOffset, SameImageAsClosedForm) {
    FfSetup st;
    for (const Placement& p : kPlacements) {
        auto r = test::render(scene(st, p.scale, p.offset, GetParam()), 32, 41);
        stability::expect_finite(r, p.label);
        auto z = test::z_against(r.film(), [&](int x, int y) { return expected_pixel(st, x, y); });
        EXPECT_LT(std::abs(z.z), test::z_threshold(kTests)) << p.label;
        EXPECT_LT(z.max_abs_z, stability::t_threshold(kTests * st.res * st.res, stability::min_dof(r.film()))) << p.label;
        std::printf("[ stability ] %s %s: image z %.2f, worst pixel z %.2f, mean %.6g, %.2f s\n",
                    stability::name_of(GetParam()), p.label, z.z, z.max_abs_z, r.report.error.image_mean,
                    r.report.elapsed_s);
    }
}

INSTANTIATE_TEST_SUITE_P(Integrators, ScaleOffset, ::testing::Values(IntegratorType::Path, IntegratorType::Bdpt),
                         [](const auto& info) { return std::string(stability::name_of(info.param)); });

// Far from the origin (1e5, float spacing 2^-7 = 1/16 pixel here) light tracing and BDPT read
// +20% and +2.1% (z 8.7) while the path tracer was exact. Two causes, both fixed and both caught
// here: (1) splats land on a grid of film positions, many exactly on pixel borders, and the
// filter's closed support gave them to both neighbours (now shared half and half); (2) a light's
// emitted ray starts off the surface by the error bound (0.04 units here), so emitted rays landed
// as if the light were 4% lower (the walk now re-anchors each hit on the ray from the vertex
// itself). At 1024 spp, against the closed form.
TEST(ScaleOffsetFarFromOrigin, SplattingIntegratorsMatchClosedForm) {
    FfSetup st;
    for (IntegratorType type : {IntegratorType::Bdpt, IntegratorType::Light}) {
        auto r = test::render(scene(st, 1.0, {1e5, -1e5, 1e5}, type), 1024, 43);
        stability::expect_finite(r, "offset 1e5");
        auto z = test::z_against(r.film(), [&](int x, int y) { return expected_pixel(st, x, y); });
        EXPECT_LT(std::abs(z.z), test::z_threshold(2)) << stability::name_of(type);
        std::printf("[ stability ] %s offset 1e5, 1024 spp: image z %.2f, mean %.6g\n", stability::name_of(type), z.z,
                    r.report.error.image_mean);
    }
}

// The test can fail: the light raised by 10% of its height is caught, at the largest scale too.
TEST(ScaleOffsetSanity, DetectsAMovedLight) {
    FfSetup st, moved;
    moved.h = 1.1;
    auto r = test::render(scene(moved, 1e6, {0, 0, 0}, IntegratorType::Path), 32, 42);
    auto z = test::z_against(r.film(), [&](int x, int y) { return expected_pixel(st, x, y); });
    EXPECT_GT(std::abs(z.z), test::z_threshold(1));
}

}  // namespace
}  // namespace omega
