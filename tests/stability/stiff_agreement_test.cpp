// One stiff scene, every integrator: a closed diffuse box of albedo 0.9 (about ten bounces a
// path, unbounded depth), lit only by a sphere light of radius 1e-3 with radiance 1e6, partly
// hidden behind a glossy block. Path tracing, light tracing and BDPT agree within the noise
// (per-block and whole-image z-tests on independent seeds, Bonferroni over all pairs).
#include <gtest/gtest.h>

#include "stability_util.h"

namespace omega {
namespace {

SceneDesc stiff_scene() {
    SceneDesc d = test::empty_scene(16, 16);
    d.integrator.max_depth = -1;
    d.sensor.to_world = Mat4::look_at({0.2, 0.1, -0.9}, {0, -0.3, 0.5}, {0, 1, 0});
    d.sensor.fov = 75;
    d.materials["wall"] = test::diffuse("wall", Rgb{0.9f, 0.9f, 0.85f});
    ConductorBsdf rough;
    rough.alpha_u = rough.alpha_v = 0.05f;
    rough.specular_reflectance = Rgb(0.9f);
    d.materials["glossy"] = MaterialDesc{"glossy", rough, {}};
    d.materials["black"] = MaterialDesc{"black", BlackBsdf{}, {}};
    ShapeDesc room;
    room.type = ShapeType::Cube;
    room.material = "wall";
    d.shapes.push_back(room);
    ShapeDesc block;
    block.type = ShapeType::Cube;
    block.to_world = Mat4::translate({0.3, -0.6, 0.4}) * Mat4::rotate({0, 1, 0}, 30) * Mat4::scale({0.3, 0.4, 0.3});
    block.material = "glossy";
    d.shapes.push_back(block);
    ShapeDesc lamp;
    lamp.type = ShapeType::Sphere;
    lamp.center = {0.45, 0.85, 0.5};
    lamp.radius = 1e-3;
    lamp.material = "black";
    lamp.emitter = EmitterDesc{Rgb(1e6f), false};
    d.shapes.push_back(lamp);
    return d;
}

struct IntegratorRun {
    IntegratorType type;
    long long spp;
};

TEST(StiffAgreement, AllIntegratorsAgree) {
    const IntegratorRun runs[] = {{IntegratorType::Path, 64}, {IntegratorType::Light, 64}, {IntegratorType::Bdpt, 32}};
    std::vector<test::RenderResult> results;
    uint64_t seed = 91;
    for (const IntegratorRun& run : runs) {
        SceneDesc d = stiff_scene();
        d.integrator.type = run.type;
        results.push_back(test::render(d, run.spp, seed++));
        stability::expect_finite(results.back(), stability::name_of(run.type));
        EXPECT_GT(results.back().report.error.image_mean, 0.0);
        std::printf("[ stability ] stiff scene %s: mean %.6g +- %.2g, %.2f s\n", stability::name_of(run.type),
                    results.back().report.error.image_mean, results.back().report.error.image_mean_stderr,
                    results.back().report.elapsed_s);
    }
    for (size_t a = 0; a < 3; ++a)
        for (size_t b = a + 1; b < 3; ++b) {
            auto z = test::z_between(results[a].film(), results[b].film(), 4);
            EXPECT_LT(z.max_abs_z, test::z_threshold(z.blocks * 3)) << stability::name_of(runs[a].type) << "-"
                                                                     << stability::name_of(runs[b].type);
            EXPECT_LT(std::abs(z.z), test::z_threshold(3)) << stability::name_of(runs[a].type) << "-"
                                                           << stability::name_of(runs[b].type);
            std::printf("[ stability ] stiff scene %s vs %s: image z %.2f, worst block z %.2f (%d blocks)\n",
                        stability::name_of(runs[a].type), stability::name_of(runs[b].type), z.z, z.max_abs_z,
                        z.blocks);
        }
}

// The test can fail: the light 10% brighter for one integrator is caught.
TEST(StiffAgreementSanity, DetectsABrighterLight) {
    SceneDesc a = stiff_scene(), b = stiff_scene();
    b.shapes[2].emitter->radiance = Rgb(1.1e6f);
    b.integrator.type = IntegratorType::Bdpt;
    auto ra = test::render(a, 64, 95);
    auto rb = test::render(b, 32, 96);
    auto z = test::z_between(ra.film(), rb.film(), 4);
    EXPECT_GT(std::abs(z.z), test::z_threshold(1));
}

}  // namespace
}  // namespace omega
