// The image is a function of (scene, seed, spp) alone: thread count and tiling never change a bit.
#include <gtest/gtest.h>


#include "render_harness.h"

namespace omega {
namespace {

SceneDesc small_scene() { return test::metal_cube_scene(40, 30); }

// A session's settings on 2 threads for the scene's integrator.
RenderSettings settings(const SceneDesc& d, uint64_t seed) {
    RenderSettings rs;
    rs.seed = seed;
    rs.threads = 2;
    rs.integrator = d.integrator;
    return rs;
}

// Samples [rs.first_sample, split) in one session, then [split, end) in a second one resumed
// from the first's film, as a checkpoint does.
Film render_resumed(const Scene& scene, const SceneDesc& d, RenderSettings rs, long long split, long long end) {
    rs.halt.spp = split;
    RenderSession first(scene, rs);
    first.run();
    rs.first_sample = split;
    rs.halt.spp = end;
    RenderSession second(scene, rs);
    second.film() = Film::deserialize(d.sensor.film, first.film().serialize());
    second.run();
    return second.film();
}

TEST(Determinism, SameImageForAnyThreadCountAndTileSize) {
    SceneDesc d = small_scene();
    auto one = test::render(d, 8, 42, 1, 32);
    auto two = test::render(d, 8, 42, 2, 32);
    auto three_small_tiles = test::render(d, 8, 42, 3, 7);
    EXPECT_TRUE(test::same_bits(one.film(), two.film()));
    EXPECT_TRUE(test::same_bits(one.film(), three_small_tiles.film()));
    EXPECT_GT(one.report.error.image_mean, 0.0);
}

TEST(Determinism, SeedChangesTheImage) {
    SceneDesc d = small_scene();
    auto a = test::render(d, 4, 1, 2);
    auto b = test::render(d, 4, 2, 2);
    EXPECT_FALSE(test::same_bits(a.film(), b.film()));
    // ...but only by noise.
    auto z = test::z_between(a.film(), b.film(), 10);
    EXPECT_LT(z.max_abs_z, test::z_threshold(z.blocks));
}

// Samples [0, 24) rendered as [0, 5) then [5, 24) in a resumed session equal one run of [0, 24),
// for every integrator, variance included: the resumed run's passes (5, then 1, 2, 4, ...) are
// not the whole run's (1, 2, 4, 8, ...), and neither may show.
TEST(Determinism, ResumedRangesMergeExactly) {
    for (SamplerType sampler : {SamplerType::Sobol, SamplerType::Independent}) {
        for (IntegratorType type : {IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt}) {
            SceneDesc d = small_scene();
            d.integrator.type = type;
            d.integrator.sampler = sampler;
            d.integrator.max_depth = 5;
            auto whole = test::render(d, 24, 5, 2);
            auto scene = Scene::build(d);
            const Film resumed = render_resumed(*scene, d, settings(d, 5), 5, 24);
            EXPECT_TRUE(test::same_bits(whole.film(), resumed)) << integrator_name(type) << " " << sampler_name(sampler);
            EXPECT_GT(whole.film().pixel(20, 15).var_of_mean.x, 0.0) << integrator_name(type);
        }
    }
}

// The sobol sampler hashes index / 2^32 into its key, and the path tracer's tile loop computes
// that key once per pixel, again where the index crosses a multiple of 2^32: a range across
// 2^32 equals its two halves, the second started at 2^32 (where the key is computed afresh).
// The whole run's passes (1, then 2 samples) put 2^32 inside its second pass.
TEST(Determinism, ARangeAcrossTwoToThe32EqualsItsHalves) {
    constexpr long long k32 = 1LL << 32;
    SceneDesc d = small_scene();
    d.integrator.max_depth = 4;
    auto scene = Scene::build(d);
    RenderSettings rs = settings(d, 9);
    rs.first_sample = k32 - 2;
    rs.halt.spp = k32 + 2;
    RenderSession whole(*scene, rs);
    whole.run();
    EXPECT_TRUE(test::same_bits(whole.film(), render_resumed(*scene, d, rs, k32, k32 + 2)));
    EXPECT_GT(whole.film().pixel(20, 15).var_of_mean.x, 0.0);
}

}  // namespace
}  // namespace omega

namespace omega {
namespace {

// Light tracing and BDPT splat onto pixels of other tiles; splats are merged in tile order, so
// the image is still bit-identical for any thread count (at a given tile size, which fixes the
// order in which splats reach a pixel).
TEST(Determinism, SplattingIntegratorsAreBitIdenticalAcrossThreads) {
    for (IntegratorType type : {IntegratorType::Light, IntegratorType::Bdpt}) {
        SceneDesc d = small_scene();
        d.integrator.type = type;
        d.integrator.max_depth = 5;
        auto one = test::render(d, 6, 42, 1, 32);
        auto two = test::render(d, 6, 42, 2, 32);
        auto three = test::render(d, 6, 42, 3, 32);
        EXPECT_TRUE(test::same_bits(one.film(), two.film())) << int(type);
        EXPECT_TRUE(test::same_bits(one.film(), three.film())) << int(type);
        // 16 workers cut the splat bands finer after the first batch (SplatBands::relayout).
        auto sixteen = test::render(d, 6, 42, 16, 32);
        EXPECT_TRUE(test::same_bits(one.film(), sixteen.film())) << int(type);
        EXPECT_GT(one.report.error.image_mean, 0.0);
    }
}

}  // namespace
}  // namespace omega
