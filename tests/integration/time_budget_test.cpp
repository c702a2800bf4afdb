// Time limits: a render ends at its limit, for every integrator, by cutting its last pass at a
// tile boundary; a cut batch of light paths still estimates the image without bias.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>

#include "render_harness.h"

namespace omega {
namespace {

using Clock = std::chrono::steady_clock;

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr double kSlack = 3.0;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
constexpr double kSlack = 3.0;
#else
constexpr double kSlack = 1.0;
#endif
#else
constexpr double kSlack = 1.0;
#endif

// The bound: within 5% of T or 0.5 s, whichever is larger (wider under a sanitizer).
TEST(TimeBudget, EndsAtTheLimitForEveryIntegrator) {
    const double limit = 1.0;
    for (IntegratorType type : {IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt}) {
        SceneDesc d = test::metal_cube_scene(128, 96);
        d.integrator.type = type;
        d.integrator.max_depth = 5;
        auto scene = Scene::build(d);
        RenderSettings rs;
        rs.threads = 2;
        rs.tile_size = 16;
        rs.integrator = d.integrator;
        rs.halt.time_s = limit;
        RenderSession session(*scene, rs);
        const auto t0 = Clock::now();
        PassReport r = session.run();
        const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
        EXPECT_GE(wall, limit) << integrator_name(type);
        EXPECT_LE(wall, limit + kSlack * std::max(0.05 * limit, 0.5)) << integrator_name(type);
        EXPECT_GE(r.spp, 1) << integrator_name(type);
        EXPECT_GT(r.error.image_mean, 0.0) << integrator_name(type);
    }
}

// A clock that advances 1 ms per reading: with one thread, the tiles of a pass read it in order,
// so the pass is cut at a known tile.
std::function<Clock::time_point()> ticking_clock(std::shared_ptr<std::atomic<int>> calls) {
    const auto t0 = Clock::time_point{};
    return [calls, t0] { return t0 + std::chrono::milliseconds(calls->fetch_add(1)); };
}

RenderSettings cut_settings(const SceneDesc& d, uint64_t seed, bool cut) {
    RenderSettings rs;
    rs.threads = 1;
    rs.tile_size = 4;  // a 16x16 film: 16 tiles, the first 8 are the top half
    rs.seed = seed;
    rs.integrator = d.integrator;
    // Batch 1 alone, on a film that (as after a resume) may be cut from its first pass on.
    rs.first_sample = 1;
    rs.halt.spp = 2;
    if (cut) {
        rs.clock = ticking_clock(std::make_shared<std::atomic<int>>(0));
        // Reading 0 starts the run; readings 1-8 let the top 8 tiles start; reading 9 (9 ms) cuts.
        rs.halt.time_s = 0.0085;
    }
    return rs;
}

double top_half_mean(const Film& f) {
    double sum = 0;
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x) {
            PixelStats p = f.pixel(x, y);
            sum += (p.mean.x + p.mean.y + p.mean.z) / 3.0;
        }
    return sum / 128.0;
}

TEST(TimeBudget, ACutPassKeepsOnlyTheTilesThatRan) {
    for (IntegratorType type : {IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt}) {
        SceneDesc d = test::metal_cube_scene(16, 16);
        d.integrator.type = type;
        d.integrator.max_depth = 5;
        auto scene = Scene::build(d);
        RenderSession session(*scene, cut_settings(d, 3, true));
        PassReport r = session.run();
        EXPECT_TRUE(r.cut) << integrator_name(type);
        EXPECT_EQ(r.spp, 1) << integrator_name(type);  // what every pixel holds: batch 1 is partial
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x)
                EXPECT_EQ(session.film().pixel(x, y).n, y < 8 ? 1u : 0u) << integrator_name(type) << " " << x << "," << y;
    }
}

// Light tracing splats most of its image from light paths; a cut batch holds half of them and
// must rescale their splats. Over many seeds, the top half of cut batches and of whole batches
// must agree (paired, since they share their samples); without the rescale they differ by about
// half the light-path part.
TEST(TimeBudget, ACutBatchOfLightPathsStaysUnbiased) {
    for (IntegratorType type : {IntegratorType::Light, IntegratorType::Bdpt}) {
        SceneDesc d = test::metal_cube_scene(16, 16);
        d.integrator.type = type;
        d.integrator.max_depth = 5;
        auto scene = Scene::build(d);
        const int seeds = 400;
        double sum = 0, sum2 = 0, whole_sum = 0;
        for (int s = 0; s < seeds; ++s) {
            RenderSession cut(*scene, cut_settings(d, uint64_t(s), true));
            cut.run();
            RenderSession whole(*scene, cut_settings(d, uint64_t(s), false));
            whole.run();
            const double w = top_half_mean(whole.film());
            const double diff = top_half_mean(cut.film()) - w;
            sum += diff;
            sum2 += diff * diff;
            whole_sum += w;
        }
        const double mean = sum / seeds;
        const double sd = std::sqrt(std::max(0.0, sum2 / seeds - mean * mean) / (seeds - 1));
        ASSERT_GT(sd, 0.0) << integrator_name(type);
        EXPECT_LT(std::abs(mean / sd), test::z_threshold(2)) << integrator_name(type) << ": mean difference " << mean
                                                             << " of a mean image value " << whole_sum / seeds;
    }
}

}  // namespace
}  // namespace omega
