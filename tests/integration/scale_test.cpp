// Robust rays: the Cornell box scaled by 1e-4, 1e5 and 1e6 renders the same image, within noise,
// as at scale 1. Self-intersection (acne) or light leaks would show as large block z-scores.
#include <gtest/gtest.h>

#include "render_harness.h"
#include "scene/scene_parser.h"

namespace omega {
namespace {

SceneDesc cornell(double scale) {
    SceneDesc d = parse_scene_file(OMEGA_SOURCE_DIR "/scenes/cornell-box.yaml");
    d.sensor.film.width = d.sensor.film.height = 48;
    d.sensor.film.has_crop = false;
    d.integrator.max_depth = -1;
    Mat4 s = Mat4::scale({scale, scale, scale});
    d.sensor.to_world = s * d.sensor.to_world;
    for (auto& sh : d.shapes) sh.to_world = s * sh.to_world;
    for (auto& l : d.lights) {
        l.position = l.position * scale;
        l.to_world = s * l.to_world;
    }
    return d;
}

class Scale : public ::testing::TestWithParam<double> {};

TEST_P(Scale, SameImageAsUnitScale) {
    auto ref = test::render(cornell(1.0), 24, 11);
    auto scaled = test::render(cornell(GetParam()), 24, 12);
    auto z = test::z_between(ref.film(), scaled.film(), 6);
    EXPECT_LT(z.max_abs_z, test::z_threshold(z.blocks * 3)) << "scale " << GetParam();
    EXPECT_LT(std::abs(z.z), test::z_threshold(3)) << "scale " << GetParam();
    EXPECT_EQ(scaled.report.nonfinite, 0u);
    EXPECT_GT(scaled.report.error.image_mean, 0.0);
}

INSTANTIATE_TEST_SUITE_P(Cornell, Scale, ::testing::Values(1e-4, 1e5, 1e6));

// The test can fail: a light 20% dimmer is caught.
TEST(ScaleSanity, DetectsADifferentImage) {
    auto ref = test::render(cornell(1.0), 24, 11);
    SceneDesc d = cornell(1.0);
    for (auto& sh : d.shapes)
        if (sh.emitter) sh.emitter->radiance = sh.emitter->radiance * 0.8f;
    auto dim = test::render(d, 24, 12);
    auto z = test::z_between(ref.film(), dim.film(), 6);
    EXPECT_GT(std::abs(z.z), test::z_threshold(1));
}

// Every example scene renders without a single non-finite sample.
TEST(ExampleScenes, RenderWithoutNonFiniteSamples) {
    for (const char* name : {"cornell-box.yaml", "veach-mis.yaml", "indirect-room.yaml"}) {
        SceneDesc d = parse_scene_file(std::string(OMEGA_SOURCE_DIR "/scenes/") + name);
        d.sensor.film.width /= 16;
        d.sensor.film.height /= 16;
        d.sensor.film.has_crop = false;
        auto r = test::render(d, 8, 1);
        EXPECT_EQ(r.report.nonfinite, 0u) << name;
        EXPECT_GT(r.report.error.image_mean, 0.0) << name;
    }
}

}  // namespace
}  // namespace omega
