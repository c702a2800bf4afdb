#pragma once
// Shared by the Tungsten-reference tests: render a scene of ../shared/scenes/materials through the
// Mitsuba importer at 1/4 of the reference resolution and z-test regions against reference.exr.
//
// With the box filter a low-resolution pixel integrates exactly the footprint of 4 x 4 reference
// pixels, so the mean of those is its expectation; no resampling bias. Variance: Omega's
// per-pixel variance of the mean (the var.* channels) plus the reference's noise, which the
// README quotes per 32 x 32-pixel block (max 0.11-0.15% depending on the scene); 0.15% is used
// for every scene, so the z-scores are slightly conservative.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "film/film.h"
#include "render_harness.h"
#include "scene/mitsuba_importer.h"
#include "shared_data.h"

namespace omega::tungsten {

constexpr int kDown = 4;                      // reference pixels per Omega pixel, per axis
constexpr double kRefBlockRelNoise = 1.5e-3;  // README: max relative noise of a 32 x 32 block mean

struct Region {
    double omega = 0, ref = 0, var = 0;
    int pixels = 0;
    double z() const { return (omega - ref) / std::sqrt(var + sqr(kRefBlockRelNoise * ref)); }
    double ratio() const { return omega / ref; }
};

// Channel mean of the reference over the footprint of Omega pixel (x, y).
inline double ref_mean(const ExrImage& ref, int x, int y) {
    double s = 0;
    for (int j = 0; j < kDown; ++j)
        for (int i = 0; i < kDown; ++i) {
            size_t k = 3 * (size_t(y * kDown + j) * size_t(ref.width) + size_t(x * kDown + i));
            s += (double(ref.rgb[k]) + ref.rgb[k + 1] + ref.rgb[k + 2]) / 3.0;
        }
    return s / (kDown * kDown);
}

inline void add(Region& r, const Film& f, const ExrImage& ref, int x, int y) {
    PixelStats p = f.pixel(x, y);
    r.omega += (p.mean.x + p.mean.y + p.mean.z) / 3.0;
    // Channels of one pixel are strongly correlated: their sd's average, as z_between does.
    double sd = (std::sqrt(p.var_of_mean.x) + std::sqrt(p.var_of_mean.y) + std::sqrt(p.var_of_mean.z)) / 3.0;
    r.var += sd * sd;
    r.ref += ref_mean(ref, x, y);
    ++r.pixels;
}

// Renders scenes/materials/<name>/scene.xml with `integrator` and z-tests, against its reference,
// one region per shape (the pixels whose centre ray hits it first; `shapes` names them in file
// order), the background (no hit), and 8 x 8 blocks of Omega pixels. The importer must not warn:
// every material of these scenes is supported. OMEGA_TUNGSTEN_SPP overrides spp. The light tracer
// cannot see the environment directly: for it, pixels whose centre ray escapes are left out of
// every region (blocks without surface pixels are then not tested).
inline void compare_with_reference(const std::string& name, IntegratorType integrator, long long spp,
                                   const char* label, const std::vector<std::string>& shapes) {
    const bool surfaces_only = integrator == IntegratorType::Light;
    const std::string dir = test::shared_path("scenes/materials/" + name);
    if (!test::shared_available(dir + "/reference.exr")) GTEST_SKIP() << dir << " not present";
    SceneDesc d = load_scene_file(dir + "/scene.xml");
    for (const auto& w : d.warnings) ADD_FAILURE() << "the importer warns: " << w;
    ExrImage ref = read_exr(dir + "/reference.exr");
    ASSERT_EQ(ref.width, 256);
    ASSERT_EQ(ref.height, 256);
    const int w = ref.width / kDown, h = ref.height / kDown;
    d.sensor.film.width = w;
    d.sensor.film.height = h;
    d.sensor.film.crop = {0, 0, w, h};
    ASSERT_EQ(d.sensor.film.filter, FilterType::Box);
    d.integrator.type = integrator;
    const char* spp_env = std::getenv("OMEGA_TUNGSTEN_SPP");
    auto r = test::render(d, spp_env ? std::atoll(spp_env) : spp, 17, 2);
    EXPECT_EQ(r.report.nonfinite, 0u);
    EXPECT_EQ(r.report.mis_errors, 0u);
    const Film& f = r.film();
    const Scene& scene = *r.scene;
    ASSERT_EQ(scene.shapes().size(), shapes.size());

    std::vector<Region> regions(shapes.size() + 1);  // the last one: background
    std::vector<Region> blocks(size_t((w / 8) * (h / 8)));
    Region all;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            Ray ray = scene.sensor().generate_ray({x + 0.5f, y + 0.5f}, {0.5f, 0.5f});
            SurfaceHit hit;
            size_t k = scene.intersect(ray, hit) ? hit.shape : shapes.size();
            if (surfaces_only) {
                // Leave out every pixel whose footprint may see the environment (probes at the
                // corners and edge midpoints): the light tracer misses that part of it.
                bool escapes = k == shapes.size();
                for (int j = 0; j < 9 && !escapes; ++j) {
                    SurfaceHit h2;
                    Ray r2 = scene.sensor().generate_ray({x + 0.5f * float(j % 3), y + 0.5f * float(j / 3)}, {0.5f, 0.5f});
                    escapes = !scene.intersect(r2, h2);
                }
                if (escapes) continue;
            }
            add(regions[k], f, ref, x, y);
            add(blocks[size_t((y / 8) * (w / 8) + x / 8)], f, ref, x, y);
            add(all, f, ref, x, y);
        }
    // Blocks with too few pixels (surfaces_only) are not tested.
    std::erase_if(blocks, [](const Region& b) { return b.pixels < 16; });
    int tested = 1 + int(blocks.size());
    for (const Region& g : regions) tested += g.pixels >= 30 && g.ref > 0;
    // Family-wise false alarm 1e-3 over every region tested.
    const double bound = test::z_threshold(tested);
    auto check = [&](const Region& g, const std::string& what) {
        std::printf("[tungsten] %s %s %-24s pixels %4d  Omega/Tungsten %.5f (sd %.5f)  z %+.2f\n", label, name.c_str(),
                    what.c_str(), g.pixels, g.ratio(), std::sqrt(g.var + sqr(kRefBlockRelNoise * g.ref)) / g.ref, g.z());
        EXPECT_TRUE(std::isfinite(g.omega)) << what;
        EXPECT_LT(std::abs(g.z()), bound) << what;
        // A gross-error guard beside the z-test (a z-test alone passes anything if the variance
        // estimate blows up).
        EXPECT_NEAR(g.ratio(), 1.0, 0.03) << what;
    };
    check(all, "whole image");
    for (size_t k = 0; k < regions.size(); ++k)
        if (regions[k].pixels >= 30 && regions[k].ref > 0) check(regions[k], k < shapes.size() ? shapes[k] : "background");
    double zmax = 0, z2 = 0;
    size_t worst = 0;
    for (size_t i = 0; i < blocks.size(); ++i) {
        const Region& b = blocks[i];
        if (std::abs(b.z()) > zmax) worst = i;
        zmax = std::max(zmax, std::abs(b.z()));
        z2 += sqr(b.z());
    }
    const Region& wb = blocks[worst];
    std::printf("[tungsten] %s %s worst block (#%zu): Omega/Tungsten %.5f, z %+.2f\n", label, name.c_str(), worst,
                wb.ratio(), wb.z());
    std::printf("[tungsten] %s %s %zu blocks of 8x8: z rms %.2f, max |z| %.2f (bound %.2f)\n", label, name.c_str(),
                blocks.size(), std::sqrt(z2 / double(blocks.size())), zmax, bound);
    EXPECT_LT(zmax, bound);
}

}  // namespace omega::tungsten
