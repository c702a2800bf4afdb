// Dielectrics at extreme indices: 1.0 (the interface does nothing: a sphere must vanish),
// 1.0001, 4.0, and total internal reflection.
// - White furnace: in a uniform environment L, a lossless dielectric (smooth, any IOR, TIR
//   included) leaves every pixel at exactly L: paths are weighted F / P(F) = 1 and the
//   1/eta^2 radiance scaling cancels on the way out. Zero variance: exact up to float rounding.
// - In a lit scene, a sphere of IOR 1.0 (and 1.0001, whose effect is far below the noise)
//   renders the same image as the scene without it, by block z-tests; its shadow must fill
//   in through the sphere (next-event shadow rays are blocked by it, BSDF-sampled paths are not).
#include <gtest/gtest.h>

#include <cmath>

#include "stability_util.h"

namespace omega {
namespace {

SceneDesc glass_furnace(float eta, bool cube, IntegratorType type) {
    SceneDesc d = test::empty_scene(12, 12);
    d.integrator.type = type;
    d.integrator.max_depth = -1;
    DielectricBsdf glass;
    glass.eta = eta;
    d.materials["glass"] = MaterialDesc{"glass", glass, {}};
    ShapeDesc s;
    s.material = "glass";
    if (cube) {
        // A rotated cube: rays entering one face meet the others beyond the critical angle.
        s.type = ShapeType::Cube;
        s.to_world = Mat4::translate({0, 0, 4}) * Mat4::rotate({1, 1, 0}, 35) * Mat4::scale({1, 1, 1});
    } else {
        s.type = ShapeType::Sphere;
        s.center = {0, 0, 3};
        s.radius = 1.2;
    }
    d.shapes.push_back(s);
    LightDesc env;
    env.type = LightType::Constant;
    env.radiance = Rgb(1.f);
    d.lights.push_back(env);
    return d;
}

// A path through glass multiplies a handful of weights (each 1 up to an ulp) and the radiance
// scaling 1/eta^2 by its inverse: a few float roundings per crossing.
constexpr double kGlassSlack = 1e-5;

struct GlassCase {
    float eta;
    bool cube;
};
const GlassCase kGlass[] = {{1.0f, false}, {1.0001f, false}, {1.5f, false}, {4.0f, false},
                            {1.5f, true},  {4.0f, true}};

class GlassFurnace : public ::testing::TestWithParam<IntegratorType> {};

TEST_P(GlassFurnace, LosslessInterfaceKeepsTheFurnaceWhite) {
    for (const GlassCase& g : kGlass) {
        auto r = test::render(glass_furnace(g.eta, g.cube, GetParam()), 8, 61);
        stability::expect_finite(r, "glass furnace");
        double z = stability::z_with_slack(r.film(), 1.0, kGlassSlack);
        EXPECT_LT(z, test::z_threshold(6 * 2)) << stability::name_of(GetParam()) << " eta " << g.eta
                                               << (g.cube ? " cube" : " sphere") << " mean " << r.report.error.image_mean;
        double worst = 0;
        Rect c = r.film().crop();
        for (int y = c.y0; y < c.y1; ++y)
            for (int x = c.x0; x < c.x1; ++x)
                worst = std::max(worst, std::abs(stability::channel_mean(r.film().pixel(x, y)) - 1.0));
        std::printf("[ stability ] %s glass furnace eta=%g %s: mean %.9g, worst pixel |L-1| %.2e, %.2f s\n",
                    stability::name_of(GetParam()), double(g.eta), g.cube ? "cube" : "sphere",
                    r.report.error.image_mean, worst, r.report.elapsed_s);
    }
}

INSTANTIATE_TEST_SUITE_P(Integrators, GlassFurnace, ::testing::Values(IntegratorType::Path, IntegratorType::Bdpt),
                         [](const auto& info) { return std::string(stability::name_of(info.param)); });

// Total internal reflection at the BSDF: from inside beyond the critical angle, every sample
// reflects with weight 1, and no transmission has any density.
TEST(TotalInternalReflection, AllReflectedBeyondCriticalAngle) {
    for (float eta : {1.5f, 4.0f}) {
        DielectricBsdf b;
        b.eta = eta;
        const float sin_c = 1.f / eta;
        for (float sin_o : {sin_c * 1.0001f, 0.9f, 0.999999f}) {
            if (sin_o <= sin_c) continue;
            float cos_o = std::sqrt(1.f - sin_o * sin_o);
            Vec3 wo{sin_o, 0.f, -cos_o};  // inside: below the surface
            Rng rng = Rng::for_sample(9, 0, 0);
            for (int i = 0; i < 200; ++i) {
                float uc = rng.next_1d();
                Vec2 u{rng.next_1d(), rng.next_1d()};
                for (TransportMode m : {TransportMode::Radiance, TransportMode::Importance}) {
                    auto bs = bsdf_sample(Bsdf(b), wo, uc, u, m);
                    ASSERT_TRUE(bs.has_value()) << eta << " " << sin_o;
                    EXPECT_TRUE(bs->lobe & kLobeReflection) << eta << " sin " << sin_o;
                    EXPECT_LT(bs->wi.z, 0.f);
                    EXPECT_FLOAT_EQ(bs->weight.x, 1.f) << eta << " sin " << sin_o;
                }
            }
        }
    }
}

TEST(TotalInternalReflectionSanity, DetectsALossyInterface) {
    SceneDesc d = glass_furnace(4.0f, true, IntegratorType::Path);
    std::get<DielectricBsdf>(d.materials["glass"].bsdf).specular_reflectance = Rgb(0.999f);
    auto r = test::render(d, 8, 62);
    EXPECT_GT(stability::z_with_slack(r.film(), 1.0, kGlassSlack), test::z_threshold(1));
}

// A floor lit by a rectangular light, with a sphere between the camera and the floor and in the
// light's way. Without the sphere, or with IOR 1, the image is the same.
SceneDesc lit_scene(std::optional<float> sphere_eta, IntegratorType type) {
    SceneDesc d = test::empty_scene(16, 16);
    d.integrator.type = type;
    d.integrator.max_depth = -1;
    d.sensor.to_world = Mat4::look_at({0, 3, -3}, {0, 0, 0}, {0, 1, 0});
    d.sensor.fov = 50;
    d.materials["floor"] = test::diffuse("floor", Rgb(0.7f));
    d.materials["black"] = MaterialDesc{"black", BlackBsdf{}, {}};
    ShapeDesc floor;
    floor.type = ShapeType::Rectangle;
    floor.to_world = Mat4::rotate({1, 0, 0}, -90) * Mat4::scale({3, 3, 1});
    floor.material = "floor";
    d.shapes.push_back(floor);
    ShapeDesc light;
    light.type = ShapeType::Rectangle;
    light.to_world = Mat4::translate({0, 2.5, 0.5}) * Mat4::rotate({1, 0, 0}, 90) * Mat4::scale({0.6, 0.6, 1});
    light.material = "black";
    light.emitter = EmitterDesc{Rgb(6.f), false};
    d.shapes.push_back(light);
    if (sphere_eta) {
        DielectricBsdf glass;
        glass.eta = *sphere_eta;
        d.materials["glass"] = MaterialDesc{"glass", glass, {}};
        ShapeDesc ball;
        ball.type = ShapeType::Sphere;
        ball.center = {0, 0.9, 0};
        ball.radius = 0.6;
        ball.material = "glass";
        d.shapes.push_back(ball);
    }
    return d;
}

class IndexOne : public ::testing::TestWithParam<IntegratorType> {};

TEST_P(IndexOne, SphereVanishes) {
    const IntegratorType t = GetParam();
    auto ref = test::render(lit_scene(std::nullopt, t), 64, 63);
    for (float eta : {1.0f, 1.0001f}) {
        auto r = test::render(lit_scene(eta, t), 64, 64);
        stability::expect_finite(r, "index one");
        auto z = test::z_between(ref.film(), r.film(), 4);
        EXPECT_LT(z.max_abs_z, test::z_threshold(z.blocks * 2 * 2)) << stability::name_of(t) << " eta " << eta;
        EXPECT_LT(std::abs(z.z), test::z_threshold(2 * 2)) << stability::name_of(t) << " eta " << eta;
        std::printf("[ stability ] %s sphere of IOR %g vs none: image z %.2f, worst block z %.2f (%d blocks)\n",
                    stability::name_of(t), double(eta), z.z, z.max_abs_z, z.blocks);
    }
}

INSTANTIATE_TEST_SUITE_P(Integrators, IndexOne, ::testing::Values(IntegratorType::Path, IntegratorType::Bdpt),
                         [](const auto& info) { return std::string(stability::name_of(info.param)); });

TEST(IndexOneSanity, DetectsARealSphere) {
    auto ref = test::render(lit_scene(std::nullopt, IntegratorType::Path), 64, 63);
    auto r = test::render(lit_scene(1.5f, IntegratorType::Path), 64, 64);
    auto z = test::z_between(ref.film(), r.film(), 4);
    EXPECT_GT(z.max_abs_z, test::z_threshold(z.blocks));
}

}  // namespace
}  // namespace omega
