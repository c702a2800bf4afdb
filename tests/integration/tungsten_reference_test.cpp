// Agreement with an independent renderer: scenes of ../shared/scenes/materials rendered by Omega
// (through the Mitsuba importer) against Tungsten's reference.exr, by per-region z-tests. The
// references were rendered with Tungsten's own model of each material, so this checks our reading of
// that model (plastic.cpp's header) end to end: importer defaults, BSDF, sampling and integrator.
//
// Affordable in CI: Omega renders at 1/4 of the reference resolution. With the box filter a
// low-resolution pixel integrates exactly the footprint of 4 x 4 reference pixels, so the mean of
// those is its expectation; no resampling bias. Variance: Omega's per-pixel variance of the mean
// (the var.* channels) plus the reference's noise, which the README quotes (relative noise of a
// 32 x 32-pixel block mean: median 0.012%, max 0.15%); the max is used, so the z-scores are
// slightly conservative.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "film/film.h"
#include "render_harness.h"
#include "scene/mitsuba_importer.h"
#include "shared_data.h"

namespace omega {
namespace {

constexpr int kDown = 4;                 // reference pixels per Omega pixel, per axis
constexpr double kRefBlockRelNoise = 1.5e-3;  // README: max relative noise of a 32 x 32 block mean

struct Region {
    double omega = 0, ref = 0, var = 0;
    int pixels = 0;
    double z() const { return (omega - ref) / std::sqrt(var + sqr(kRefBlockRelNoise * ref)); }
    double ratio() const { return omega / ref; }
};

// Channel mean of the reference over the footprint of Omega pixel (x, y).
double ref_mean(const ExrImage& ref, int x, int y) {
    double s = 0;
    for (int j = 0; j < kDown; ++j)
        for (int i = 0; i < kDown; ++i) {
            size_t k = 3 * (size_t(y * kDown + j) * size_t(ref.width) + size_t(x * kDown + i));
            s += (double(ref.rgb[k]) + ref.rgb[k + 1] + ref.rgb[k + 2]) / 3.0;
        }
    return s / (kDown * kDown);
}

void add(Region& r, const Film& f, const ExrImage& ref, int x, int y) {
    PixelStats p = f.pixel(x, y);
    r.omega += (p.mean.x + p.mean.y + p.mean.z) / 3.0;
    // Channels of one pixel are strongly correlated: their sd's average, as z_between does.
    double sd = (std::sqrt(p.var_of_mean.x) + std::sqrt(p.var_of_mean.y) + std::sqrt(p.var_of_mean.z)) / 3.0;
    r.var += sd * sd;
    r.ref += ref_mean(ref, x, y);
    ++r.pixels;
}

void plastic_spheres(IntegratorType integrator, long long spp, const char* label) {
    const std::string dir = test::shared_path("scenes/materials/plastic-spheres");
    if (!test::shared_available(dir + "/reference.exr")) GTEST_SKIP() << dir << " not present";
    SceneDesc d = load_scene_file(dir + "/scene.xml");
    for (const auto& w : d.warnings) ADD_FAILURE() << "the importer warns: " << w;  // all of it is supported
    ExrImage ref = read_exr(dir + "/reference.exr");
    ASSERT_EQ(ref.width, 256);
    ASSERT_EQ(ref.height, 256);
    const int w = ref.width / kDown, h = ref.height / kDown;
    d.sensor.film.width = w;
    d.sensor.film.height = h;
    d.sensor.film.crop = {0, 0, w, h};
    ASSERT_EQ(d.sensor.film.filter, FilterType::Box);
    d.integrator.type = integrator;
    // OMEGA_TUNGSTEN_SPP overrides, for sharper figures by hand.
    const char* spp_env = std::getenv("OMEGA_TUNGSTEN_SPP");
    auto r = test::render(d, spp_env ? std::atoll(spp_env) : spp, 17, 2);
    EXPECT_EQ(r.report.nonfinite, 0u);
    EXPECT_EQ(r.report.mis_errors, 0u);
    const Film& f = r.film();

    // Regions: each sphere (pixels whose centre ray hits it), the rest (floor, light, background),
    // and blocks of 8 x 8 Omega pixels (32 x 32 reference pixels, the README's 8 x 8 grid).
    const char* names[] = {"smooth plastic (red)", "rough GGX 0.05 (green)", "rough GGX 0.2 (blue)",
                           "rough GGX 0.5 (yellow)", "floor, light and background"};
    Region spheres[5];
    double red_r = 0, red_g = 0;  // reference colour of region 0
    std::vector<Region> blocks(size_t((w / 8) * (h / 8)));
    const Scene& scene = *r.scene;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            Ray ray = scene.sensor().generate_ray({x + 0.5f, y + 0.5f}, {0.5f, 0.5f});
            SurfaceHit hit;
            int k = 4;
            // Shapes in file order: floor, light, then the four spheres left to right.
            if (scene.intersect(ray, hit) && hit.shape >= 2) k = int(hit.shape) - 2;
            add(spheres[k], f, ref, x, y);
            if (k == 0) {
                size_t c = 3 * (size_t(y * kDown + kDown / 2) * size_t(ref.width) + size_t(x * kDown + kDown / 2));
                red_r += ref.rgb[c];
                red_g += ref.rgb[c + 1];
            }
            add(blocks[size_t((y / 8) * (w / 8) + x / 8)], f, ref, x, y);
        }
    // The smooth sphere must look red in the reference, or the regions are mislabelled.
    ASSERT_GT(red_r, 2 * red_g);
    for (const Region& s : spheres) ASSERT_GT(s.pixels, 30);

    // 5 regions + 64 blocks, family-wise false alarm 1e-3.
    const double bound = test::z_threshold(5 + int(blocks.size()));
    for (int k = 0; k < 5; ++k) {
        const Region& g = spheres[k];
        std::printf("[tungsten] %s plastic-spheres %-28s pixels %4d  Omega/Tungsten %.5f (sd %.5f)  z %+.2f\n", label,
                    names[k], g.pixels, g.ratio(), std::sqrt(g.var + sqr(kRefBlockRelNoise * g.ref)) / g.ref, g.z());
        EXPECT_LT(std::abs(g.z()), bound) << names[k];
        // A gross-error guard beside the z-test (a z-test alone passes anything if the variance
        // estimate blows up).
        EXPECT_NEAR(g.ratio(), 1.0, 0.03) << names[k];
    }
    double zmax = 0, z2 = 0;
    size_t worst = 0;
    for (size_t i = 0; i < blocks.size(); ++i) {
        const Region& b = blocks[i];
        if (std::abs(b.z()) > zmax) worst = i;
        zmax = std::max(zmax, std::abs(b.z()));
        z2 += sqr(b.z());
    }
    const Region& wb = blocks[worst];
    std::printf("[tungsten] %s worst block (%zu, %zu) of 8: Omega/Tungsten %.5f, z %+.2f\n", label, worst % size_t(w / 8),
                worst / size_t(w / 8), wb.ratio(), wb.z());
    std::printf("[tungsten] %s plastic-spheres 8x8 blocks: z rms %.2f, max |z| %.2f (bound %.2f)\n", label,
                std::sqrt(z2 / double(blocks.size())), zmax, bound);
    EXPECT_LT(zmax, bound);
}

// Path tracing: 2048 spp, about 10 s on 2 threads, region noise 0.2-0.6%.
TEST(TungstenReference, PlasticSpheresPath) { plastic_spheres(IntegratorType::Path, 2048, "path"); }

// Bdpt meets the coat from both ends (light subpaths in importance mode, the smooth coat's mirror
// choice, connections through eval): fewer spp for the same time.
TEST(TungstenReference, PlasticSpheresBdpt) { plastic_spheres(IntegratorType::Bdpt, 512, "bdpt"); }

}  // namespace
}  // namespace omega
