// Light path expression outputs rendered end to end: a partition of path space sums to the
// beauty image for every integrator; each output agrees across path, light and bdpt by block
// z-test; the beauty image does not change by a bit when AOVs are added; AOVs are as
// deterministic as the beauty.
#include <gtest/gtest.h>

#include <cmath>

#include "render_harness.h"

namespace omega {
namespace {

const IntegratorType kAll[] = {IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt};

const char* name_of(IntegratorType t) {
    return t == IntegratorType::Path ? "path" : t == IntegratorType::Light ? "light" : "bdpt";
}

// Every path L x* E (x one of S, D, G) is in exactly one of these (lpe_test checks it on all
// strings up to length 6).
std::vector<AovDesc> partition() {
    return {{"emitted", "L E"}, {"direct", "L D E"}, {"indirect", "L D D+ E"}, {"specular", "L .* S .* E"}};
}

// The metal cube scene (D floor, G rough metal, alpha 0.2) with a smooth glass ball in view:
// every vertex class occurs.
SceneDesc all_classes_scene() {
    SceneDesc d = test::metal_cube_scene(16, 12);
    DielectricBsdf glass;
    glass.eta = 1.5f;
    d.materials["glass"] = MaterialDesc{"glass", glass, {}};
    ShapeDesc ball;
    ball.type = ShapeType::Sphere;
    ball.center = {-0.9, 0.35, 0};
    ball.radius = 0.35;
    ball.material = "glass";
    d.shapes.push_back(ball);
    return d;
}

const Film& aov(const test::RenderResult& r, size_t i) { return r.session->aovs()->films()[i].film; }

// Renders with `aovs` whose first `parts` entries partition path space, for every integrator,
// and checks that they sum to the beauty within float rounding, and that each is lit.
void expect_partition(const std::vector<AovDesc>& aovs, size_t parts, bool product) {
    ASSERT_EQ(LpeSet(aovs).has_products(), product);
    for (IntegratorType t : kAll) {
        SceneDesc d = all_classes_scene();
        d.integrator.type = t;
        d.sensor.film.aovs = aovs;
        auto r = test::render(d, 16, 7, 2);
        ASSERT_NE(r.session->aovs(), nullptr);
        ASSERT_EQ(r.session->aovs()->size(), aovs.size());
        EXPECT_EQ(r.report.nonfinite, 0u);
        const Film& beauty = r.film();
        const Rect c = beauty.crop();
        double worst = 0, total = 0;
        std::vector<double> part_total(parts, 0.0);
        for (int y = c.y0; y < c.y1; ++y)
            for (int x = c.x0; x < c.x1; ++x) {
                const PixelStats b = beauty.pixel(x, y);
                for (int ch = 0; ch < 3; ++ch) {
                    double sum = 0, mag = std::abs(b.mean[ch]);
                    for (size_t a = 0; a < parts; ++a) {
                        const double v = aov(r, a).pixel(x, y).mean[ch];
                        ASSERT_TRUE(std::isfinite(v));
                        sum += v;
                        mag += std::abs(v);
                        part_total[a] += v;
                    }
                    worst = std::max(worst, std::abs(sum - b.mean[ch]) / std::max(mag, 1e-30));
                    total += b.mean[ch];
                }
            }
        EXPECT_LT(worst, 1e-5) << name_of(t) << ": parts differ from the beauty beyond float rounding";
        EXPECT_GT(total, 0.0) << name_of(t);
        for (size_t a = 0; a < parts; ++a) {
            if (aovs[a].name == "emitted") continue;  // the light is not in view
            EXPECT_GT(part_total[a], 0.0) << name_of(t) << " " << aovs[a].name;
        }
    }
}

TEST(LpeAov, PartitionSumsToTheBeauty) {
    // By class: direct, indirect and specular light all reach the image (the light is not seen).
    expect_partition(partition(), 4, true);
    // By length modulo 3, next to counters that make the product automaton too large (their
    // joint period, 3 * 5 * 7 * 11, is over kMaxProductStates): the path tracer and BDPT then
    // step each AOV's automaton on its own.
    expect_partition({{"k1", "L (. . .)* E"}, {"k2", "L . (. . .)* E"}, {"k0", "L . . (. . .)* E"}, {"upto25", "L .{0,25} E"},
                      {"mod5", "L (. . . . .)* E"}, {"mod7", "L (. . . . . . .)* E"},
                      {"mod11", "L (. . . . . . . . . . .)* E"}},
                     3, false);
}

TEST(LpeAov, BeautyUnchangedAndDeterministic) {
    for (IntegratorType t : kAll) {
        SceneDesc plain = all_classes_scene();
        plain.integrator.type = t;
        SceneDesc with = plain;
        with.sensor.film.aovs = partition();
        with.sensor.film.aovs.push_back({"glossy", "L .* G .* E"});
        // Splats are merged in tile order, so the tiling stays the same; the thread count changes.
        auto a = test::render(plain, 4, 3, 1, 8);
        auto b = test::render(with, 4, 3, 2, 8);
        auto c = test::render(with, 4, 3, 1, 8);
        EXPECT_TRUE(test::same_bits(a.film(), b.film())) << name_of(t) << ": AOVs changed the beauty";
        for (size_t i = 0; i < b.session->aovs()->size(); ++i)
            EXPECT_TRUE(test::same_bits(aov(b, i), aov(c, i))) << name_of(t) << " aov " << i << ": thread count changed it";
    }
}

// The glass caustic scene (test::glass_caustic_scene) with a caustic, direct and bounded AOV.
SceneDesc caustic_scene() {
    SceneDesc d = test::glass_caustic_scene(0.4, 8.f);
    d.sensor.film.aovs = {{"caustic", "L S+ D E"}, {"direct", "L D E"}, {"bounded", "L .{1,2} E"}};
    return d;
}

struct Run {
    IntegratorType t;
    long long spp;
    uint64_t seed;
};

// Renders `d` with each run's integrator and checks every AOV pairwise by block z-test
// (8 x 8 blocks: light tracing reaches dim regions in few pixels per batch, and block sums are
// closer to normal than single sparse pixels). Each AOV must be lit.
void expect_aovs_agree(const SceneDesc& d, const std::vector<Run>& runs, const char* scene) {
    std::vector<test::RenderResult> results;
    for (const Run& run : runs) {
        SceneDesc di = d;
        di.integrator.type = run.t;
        results.push_back(test::render(di, run.spp, run.seed, 2));
        EXPECT_EQ(results.back().report.nonfinite, 0u);
        EXPECT_EQ(results.back().report.mis_errors, 0u);
    }
    const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    const size_t n = d.sensor.film.aovs.size();
    const Rect c = results[0].film().crop();
    for (size_t a = 0; a < n; ++a) {
        double mean = 0;
        const Film& f = aov(results[2], a);
        for (int y = c.y0; y < c.y1; ++y)
            for (int x = c.x0; x < c.x1; ++x) mean += f.pixel(x, y).mean.x;
        EXPECT_GT(mean, 0.0) << scene << " " << d.sensor.film.aovs[a].name << " is black";
        for (const auto& p : pairs) {
            const auto z = test::z_between(aov(results[size_t(p[0])], a), aov(results[size_t(p[1])], a), 8);
            const std::string what = std::string(scene) + " " + d.sensor.film.aovs[a].name + " " +
                                     name_of(runs[size_t(p[0])].t) + "-" + name_of(runs[size_t(p[1])].t);
            EXPECT_LT(z.max_abs_z, test::z_threshold(z.blocks * 3 * int(n))) << what << ": worst block";
            EXPECT_LT(std::abs(z.z), test::z_threshold(3 * int(n))) << what << ": image";
        }
    }
}

TEST(LpeAov, EachOutputAgreesAcrossIntegrators) {
    expect_aovs_agree(caustic_scene(),
                      {{IntegratorType::Path, 1024, 11}, {IntegratorType::Light, 512, 12}, {IntegratorType::Bdpt, 256, 13}},
                      "caustic");
    // Glossy vertices (the rough metal cube, alpha 0.2): G on its own, and D that excludes G
    // because the expression mentions it.
    SceneDesc g = test::metal_cube_scene(16, 16);
    g.integrator.max_depth = 5;
    g.sensor.film.aovs = {{"glossy_seen", "L .* G E"}, {"diffuse_direct", "L G* D E"}, {"via_glossy", "L .* G .* D E"}};
    expect_aovs_agree(g, {{IntegratorType::Path, 256, 21}, {IntegratorType::Light, 256, 22}, {IntegratorType::Bdpt, 128, 23}},
                      "metal cube");
}

}  // namespace
}  // namespace omega

namespace omega {
namespace {

// What the daemon does at a checkpoint: the beauty and every AOV serialized at a pass boundary,
// restored into a new session that renders on from there. Bit-identical to one render.
TEST(LpeAov, ResumeFromSerializedFilmsIsExact) {
    for (IntegratorType t : kAll) {
        SceneDesc d = all_classes_scene();
        d.integrator.type = t;
        d.sensor.film.aovs = partition();
        auto scene = Scene::build(d);
        auto settings = [&](long long first, long long end) {
            RenderSettings rs;
            rs.seed = 9;
            rs.threads = 2;
            rs.integrator = d.integrator;
            rs.first_sample = first;
            rs.halt.spp = end;
            return rs;
        };
        RenderSession whole(*scene, settings(0, 6));
        whole.run();
        RenderSession first(*scene, settings(0, 2));
        first.run();
        RenderSession rest(*scene, settings(2, 6));
        rest.film() = Film::deserialize(d.sensor.film, first.film().serialize());
        for (size_t i = 0; i < rest.aovs()->size(); ++i)
            rest.aovs()->films()[i].film = Film::deserialize(d.sensor.film, first.aovs()->films()[i].film.serialize());
        rest.run();
        EXPECT_TRUE(test::same_bits(whole.film(), rest.film())) << name_of(t);
        for (size_t i = 0; i < whole.aovs()->size(); ++i)
            EXPECT_TRUE(test::same_bits(whole.aovs()->films()[i].film, rest.aovs()->films()[i].film)) << name_of(t) << " " << i;
    }
}

}  // namespace
}  // namespace omega

#include "integrator/bdpt_lpe.h"
#include "pathspace/path_signature.h"
#include "pathspace/subpath.h"

namespace omega {
namespace {

// BDPT decides each strategy from per-subpath automaton states (integrator/bdpt_lpe.h); reading
// the strategy's whole signature (pathspace/path_signature.h) must give the same matches, for
// every (s, t) of many sampled subpath pairs with every vertex class present. Checked with the
// product automata, without any G (no BSDF queries) and with a set too large for a product.
void expect_matcher_agrees(const std::vector<AovDesc>& aovs, bool product) {
    SceneDesc d = all_classes_scene();
    auto scene = Scene::build(d);
    const LpeSet set(aovs);
    ASSERT_EQ(set.has_products(), product);
    WalkLimits cam_lim{8, 1000}, light_lim{7, 1000};
    TracerStats stats;
    const Sensor& sensor = scene->sensor();
    BdptLpeMatcher matcher;
    std::vector<VertexClass> sig;
    int checked = 0;
    uint32_t seen = 0;
    for (int i = 0; i < 6000; ++i) {
        Sampler rng(Rng::for_sample(7, 0, uint64_t(i)));
        Vec2 film{rng.next_1d() * float(sensor.width), rng.next_1d() * float(sensor.height)};
        Ray ray = sensor.generate_ray(film, {rng.next_1d(), rng.next_1d()});
        std::vector<PathVertex> cam, lit;
        const int nc = generate_camera_subpath(*scene, ray, cam_lim, rng, stats, cam);
        const int nl = generate_light_subpath(*scene, light_lim, rng, stats, lit);
        matcher.prepare(set, lit, nl, cam, nc);
        for (int t = 1; t <= nc; ++t)
            for (int s = 0; s <= nl; ++s) {
                if (s + t - 1 < 1 || (s == 0 && cam[size_t(t - 1)].light < 0)) continue;
                strategy_signature(lit, cam, s, t, sig);
                const uint32_t want = set.match(sig);
                ASSERT_EQ(matcher.match(s, t), want) << "s " << s << " t " << t;
                seen |= want;
                ++checked;
            }
        for (int s = 1; s <= nl; ++s) {
            lens_signature(lit, s, sig);
            ASSERT_EQ(matcher.match_lens(s), set.match(sig)) << "lens s " << s;
        }
    }
    EXPECT_GT(checked, 10000);
    EXPECT_EQ(seen, (1u << aovs.size()) - 1) << "some AOV was never matched";
}

TEST(LpeAov, SubpathMatcherAgreesWithWholeSignatures) {
    std::vector<AovDesc> aovs = partition();
    aovs.push_back({"caustic", "L S+ D E"});
    aovs.push_back({"short", "L .{0,2} E"});
    aovs.push_back({"seen_in_glass", "L .* D S+ E"});
    expect_matcher_agrees(aovs, true);  // no G: D stands for every non-delta vertex
    aovs.push_back({"glossy", "L .* G .* E"});
    aovs.push_back({"direct_rough", "L (S|G)* D E"});  // G mentioned: this D is non-glossy only
    expect_matcher_agrees(aovs, true);
    // Counters of lengths 26, 3, 5 and 7 together: over kMaxProductStates tuples (the G
    // automaton doubles them).
    expect_matcher_agrees({{"upto25", "L .{0,25} E"}, {"mod3", "L (. . .)* E"}, {"mod5", "L (. . . . .)* E"},
                           {"mod7", "L (. . . . . . .)* E"}, {"glossy", "L .* G .* E"}},
                          false);
}

}  // namespace
}  // namespace omega

namespace omega {
namespace {

// A daemon tile with AOV layers still decodes as the beauty for clients that know only R, G, B
// and var.* (omega watch, the web view decode tiles with decode_exr_memory).
TEST(LpeAov, TilesWithLayersDecodeAsTheBeauty) {
    SceneDesc d = all_classes_scene();
    d.sensor.film.aovs = partition();
    auto r = test::render(d, 2, 1, 2);
    const Film& film = r.film();
    const Rect tile{4, 2, 12, 10};
    ExrMeta meta;
    append_aov_tile_layers(r.session->aovs()->films(), tile, meta);
    ASSERT_EQ(meta.layers.size(), 8u);
    EXPECT_EQ(meta.layers[0].name, "aov.emitted");
    EXPECT_EQ(meta.layers[1].name, "aov.emitted.var");
    const std::vector<uint8_t> bytes = encode_exr_tile(film, tile, meta);
    const ExrImage img = decode_exr_memory(bytes);
    ASSERT_EQ(img.width, 8);
    ASSERT_EQ(img.height, 8);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
            for (int c = 0; c < 3; ++c)
                EXPECT_EQ(img.rgb[3 * size_t(y * 8 + x) + size_t(c)], float(film.pixel(tile.x0 + x, tile.y0 + y).mean[c]));
}

}  // namespace
}  // namespace omega
