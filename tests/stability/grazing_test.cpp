// Grazing light and grazing view, cos down to 1e-6, over a large axis-aligned diffuse floor.
// - Directional light at cos c with irradiance 1/c (on a plane facing it): the floor's radiance
//   rho/pi does not depend on c. The estimator has zero variance (a delta light, next-event
//   estimation only), so the check is exact up to float rounding.
// - An orthographic camera looking at the floor at cos c under a uniform environment L: every
//   pixel is rho L (MIS of environment and BSDF sampling, z-tested against the noise).
// - Both at once. Self-intersection of the nearly tangent rays would darken the floor.
#include <gtest/gtest.h>

#include <cmath>

#include "stability_util.h"

namespace omega {
namespace {

const double kCos[] = {1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6};
constexpr float kRho = 0.8f;

// Camera looking at the floor's centre from direction (sin, 0, cos) * distance, i.e. at cos
// view_cos to the normal. Far enough back that the whole (tilted) film is above the floor.
SceneDesc floor_scene(double view_cos, IntegratorType type) {
    SceneDesc d = test::empty_scene(8, 8);
    d.integrator.type = type;
    d.integrator.max_depth = -1;
    d.sensor.type = SensorType::Orthographic;
    const double half = 1e-3;
    const double s = std::sqrt(1 - view_cos * view_cos);
    const double dist = 4 * half / view_cos;
    Vec3d eye{s * dist, 0, view_cos * dist};
    Vec3d up = view_cos > 0.5 ? Vec3d{0, 1, 0} : Vec3d{0, 0, 1};
    d.sensor.to_world = Mat4::look_at(eye, {0, 0, 0}, up) * Mat4::scale({half, half, 1});
    d.materials["floor"] = test::diffuse("floor", Rgb(kRho));
    ShapeDesc floor;
    floor.type = ShapeType::Rectangle;
    const double extent = 20 * half / view_cos;  // covers the stretched footprint (5 * half / cos)
    floor.to_world = Mat4::scale({extent, extent, 1});
    floor.material = "floor";
    d.shapes.push_back(floor);
    return d;
}

void add_sun(SceneDesc& d, double light_cos) {
    LightDesc sun;
    sun.type = LightType::Directional;
    sun.direction = {std::sqrt(1 - light_cos * light_cos), 0.0, -light_cos};  // towards the floor
    sun.irradiance = Rgb(float(1.0 / light_cos));
    d.lights.push_back(sun);
}

// The float irradiance times the float cosine the renderer can at best compute.
double sun_expected(double light_cos) { return double(kRho) / kPiD * double(float(1.0 / light_cos)) * light_cos; }

// Zero-variance estimates of rho E cos / pi: each of E, the direction's cosine, rho and 1/pi is
// one float rounding, the products a few more. 1e-6 relative covers that, nothing more.
constexpr double kSunSlack = 1e-6;

class Grazing : public ::testing::TestWithParam<IntegratorType> {};

TEST_P(Grazing, GrazingLight) {
    for (double c : kCos) {
        SceneDesc d = floor_scene(1.0, GetParam());
        add_sun(d, c);
        auto r = test::render(d, 4, 51);
        stability::expect_finite(r, "grazing light");
        double z = stability::z_with_slack(r.film(), sun_expected(c), kSunSlack);
        EXPECT_LT(z, test::z_threshold(6 * 3 * 2)) << "cos " << c << " mean " << r.report.error.image_mean
                                                    << " expected " << sun_expected(c);
        std::printf("[ stability ] %s grazing light cos=%g: mean %.9g expected %.9g (rel %.1e)\n",
                    stability::name_of(GetParam()), c, r.report.error.image_mean, sun_expected(c),
                    r.report.error.image_mean / sun_expected(c) - 1);
    }
}

TEST_P(Grazing, GrazingView) {
    for (double c : kCos) {
        SceneDesc d = floor_scene(c, GetParam());
        LightDesc env;
        env.type = LightType::Constant;
        env.radiance = Rgb(1.f);
        d.lights.push_back(env);
        auto r = test::render(d, 64, 52);
        stability::expect_finite(r, "grazing view");
        auto z = test::z_against(r.film(), [](int, int) { return double(kRho); });
        EXPECT_LT(std::abs(z.z), test::z_threshold(6 * 3 * 2)) << "cos " << c << " mean " << r.report.error.image_mean;
        EXPECT_LT(z.max_abs_z, stability::t_threshold(6 * 3 * 2 * 64, stability::min_dof(r.film()))) << "cos " << c;
        std::printf("[ stability ] %s grazing view cos=%g: mean %.6g expected %.6g, z %.2f, worst pixel z %.2f\n",
                    stability::name_of(GetParam()), c, r.report.error.image_mean, double(kRho), z.z, z.max_abs_z);
    }
}

TEST_P(Grazing, GrazingLightAndView) {
    for (double c : kCos) {
        SceneDesc d = floor_scene(c, GetParam());
        add_sun(d, c);
        auto r = test::render(d, 4, 53);
        stability::expect_finite(r, "grazing both");
        double z = stability::z_with_slack(r.film(), sun_expected(c), kSunSlack);
        EXPECT_LT(z, test::z_threshold(6 * 3 * 2)) << "cos " << c << " mean " << r.report.error.image_mean
                                                    << " expected " << sun_expected(c);
        std::printf("[ stability ] %s grazing light+view cos=%g: mean %.9g expected %.9g (rel %.1e)\n",
                    stability::name_of(GetParam()), c, r.report.error.image_mean, sun_expected(c),
                    r.report.error.image_mean / sun_expected(c) - 1);
    }
}

INSTANTIATE_TEST_SUITE_P(Integrators, Grazing, ::testing::Values(IntegratorType::Path, IntegratorType::Bdpt),
                         [](const auto& info) { return std::string(stability::name_of(info.param)); });

// The tests can fail: a 1e-5 relative error in the exact case, and a 2% error under the
// environment, are both caught.
TEST(GrazingSanity, DetectsWrongValues) {
    SceneDesc d = floor_scene(1e-3, IntegratorType::Path);
    add_sun(d, 1e-3);
    auto r = test::render(d, 4, 54);
    EXPECT_GT(stability::z_with_slack(r.film(), sun_expected(1e-3) * (1 + 1e-5), kSunSlack), test::z_threshold(1));
    SceneDesc e = floor_scene(1e-3, IntegratorType::Path);
    LightDesc env;
    env.type = LightType::Constant;
    env.radiance = Rgb(1.f);
    e.lights.push_back(env);
    auto re = test::render(e, 64, 55);
    auto z = test::z_against(re.film(), [](int, int) { return 1.02 * double(kRho); });
    EXPECT_GT(std::abs(z.z), test::z_threshold(1));
}

}  // namespace
}  // namespace omega
