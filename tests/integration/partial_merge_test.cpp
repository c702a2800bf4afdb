// Partial renders merge into the single render of the same range (film/partial_exr.h): for every
// integrator and sampler and for splits into 1, 2, 3 and 7 uneven parts, written to EXR and read back as
// `omega merge` does. Mismatched, overlapping and gapped parts are refused with the files named.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "film/partial_exr.h"
#include "render_harness.h"

namespace fs = std::filesystem;

namespace omega {
namespace {

SceneDesc box_scene() {
    SceneDesc d = test::metal_cube_scene(24, 18);
    d.integrator.max_depth = 5;
    return d;
}

class PartialMerge : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("omega_partial_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    // Renders [begin, end) on an empty film and writes it as a part; returns its path.
    std::string part(const SceneDesc& d, const Scene& scene, SampleRange r, uint64_t seed = 5,
                     const std::string& hash = "h0") {
        RenderSettings rs;
        rs.seed = seed;
        rs.threads = 2;
        rs.integrator = d.integrator;
        rs.first_sample = r.begin;
        rs.halt.spp = r.end;
        RenderSession s(scene, rs);
        s.run();
        const std::string path = (dir_ / ("part" + std::to_string(++parts_) + "_" + std::to_string(r.begin) + "_" +
                                          std::to_string(r.end) + ".exr"))
                                     .string();
        ExrMeta meta;
        meta.spp = r.size();
        write_partial_exr(path, s.film(), meta,
                          PartInfo{{r}, hash, seed, integrator_name(d.integrator.type), sampler_name(d.integrator.sampler)});
        return path;
    }

    MergeResult merge(const std::vector<std::string>& paths, bool allow_gaps = false) {
        std::vector<PartialRender> parts;
        for (const auto& p : paths) parts.push_back(read_partial_exr(p));
        return merge_parts(std::move(parts), allow_gaps);
    }

    fs::path dir_;
    int parts_ = 0;
};

struct Agreement {
    double max_rel = 0;      // over means and variances, in float as the EXR holds them
    long long values = 0, identical = 0;
};

Agreement compare(const Film& a, const Film& b) {
    Agreement g;
    const Rect c = a.crop();
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            const PixelStats pa = a.pixel(x, y), pb = b.pixel(x, y);
            EXPECT_EQ(pa.n, pb.n);
            for (int k = 0; k < 3; ++k)
                for (auto [u, v] : {std::pair{pa.mean[k], pb.mean[k]}, std::pair{pa.var_of_mean[k], pb.var_of_mean[k]}}) {
                    const float fu = float(u), fv = float(v);
                    ++g.values;
                    if (std::bit_cast<uint32_t>(fu) == std::bit_cast<uint32_t>(fv)) ++g.identical;
                    const double scale = std::max(std::abs(double(fu)), std::abs(double(fv)));
                    if (scale > 0) g.max_rel = std::max(g.max_rel, std::abs(double(fu) - double(fv)) / scale);
                    EXPECT_TRUE(std::isfinite(fu) && std::isfinite(fv));
                }
        }
    return g;
}

TEST_F(PartialMerge, AnySplitEqualsTheSingleRender) {
    const std::vector<std::vector<long long>> splits = {
        {0, 24}, {0, 11, 24}, {0, 1, 20, 24}, {0, 2, 3, 7, 8, 15, 16, 24}};
    // Sobol' parts cut at unaligned sample indices (11, 7...) still merge exactly: a sample's
    // values depend only on (seed, pixel, index, dimension).
    for (SamplerType sampler : {SamplerType::Sobol, SamplerType::Independent}) {
        for (IntegratorType type : {IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt}) {
            SceneDesc d = box_scene();
            d.integrator.type = type;
            d.integrator.sampler = sampler;
            auto whole = test::render(d, 24, 5, 2);
            auto scene = Scene::build(d);
            for (const auto& cuts : splits) {
                std::vector<std::string> paths;
                // Given out of order: the merge sorts by range, so the order of arguments cannot matter.
                for (size_t i = cuts.size() - 1; i > 0; --i) paths.push_back(part(d, *scene, {cuts[i - 1], cuts[i]}));
                MergeResult m = merge(paths);
                const std::string what = std::string(integrator_name(type)) + " " + sampler_name(sampler) + ", " +
                                         std::to_string(paths.size()) + " part(s)";
                EXPECT_EQ(format_ranges(m.part.ranges), "0:24") << what;
                EXPECT_EQ(m.meta.spp, 24) << what;
                EXPECT_TRUE(m.gaps.empty()) << what;
                const Agreement g = compare(whole.film(), m.film);
                EXPECT_LE(g.max_rel, 1e-6) << what;
                // Double rounding differs between Welford and Chan's update, so a float that straddles
                // a rounding boundary may differ by an ulp; nearly all must not.
                EXPECT_GE(double(g.identical), 0.99 * double(g.values)) << what;
                std::printf("  %s: %lld of %lld float values bit-identical, max relative difference %.3g\n", what.c_str(),
                            g.identical, g.values, g.max_rel);
                if (paths.size() == 1) {
                    EXPECT_EQ(g.identical, g.values) << what;  // one part is the render itself
                }
                // A merge's output is a part too: written and merged again, it changes nothing.
                const std::string again = (dir_ / "again.exr").string();
                write_partial_exr(again, m.film, m.meta, m.part);
                EXPECT_EQ(compare(m.film, read_partial_exr(again).film).identical, g.values) << what;
                for (const auto& p : paths) fs::remove(p);
            }
        }
    }
}

TEST_F(PartialMerge, MergesNest) {
    SceneDesc d = box_scene();
    auto scene = Scene::build(d);
    const std::string a = part(d, *scene, {0, 4}), b = part(d, *scene, {4, 9}), c = part(d, *scene, {9, 12});
    MergeResult ab = merge({a, b});
    const std::string ab_path = (dir_ / "ab.exr").string();
    write_partial_exr(ab_path, ab.film, ab.meta, ab.part);
    MergeResult nested = merge({c, ab_path});
    MergeResult flat = merge({a, b, c});
    EXPECT_EQ(format_ranges(nested.part.ranges), "0:12");
    // ((a+b)+c) either way: the same operations in the same order.
    EXPECT_EQ(compare(flat.film, nested.film).identical, compare(flat.film, flat.film).values);
}

TEST_F(PartialMerge, RefusesWhatDoesNotFitAndNamesTheFiles) {
    SceneDesc d = box_scene();
    auto scene = Scene::build(d);
    const std::string a = part(d, *scene, {0, 4}), b = part(d, *scene, {4, 8}), c = part(d, *scene, {10, 12});
    auto refused = [&](const std::vector<std::string>& paths, const std::vector<std::string>& needles) {
        try {
            merge(paths);
            ADD_FAILURE() << "merged";
        } catch (const MergeRefused& e) {
            for (const auto& n : needles) EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what();
        }
    };
    refused({a, part(d, *scene, {3, 6})}, {"overlap", a, "3:6"});
    refused({a, b, c}, {"8:10", "are in no part", b, c, "--allow-gaps"});
    refused({a, part(d, *scene, {4, 8}, 6)}, {"seed 6 differs", a});
    refused({a, part(d, *scene, {4, 8}, 5, "other")}, {"scene hash", a});
    SceneDesc bdpt = d;
    bdpt.integrator.type = IntegratorType::Bdpt;
    const std::string bd = (dir_ / "bdpt.exr").string();
    fs::rename(part(bdpt, *scene, {4, 8}), bd);
    refused({a, bd}, {"integrator bdpt differs", bd});
    SceneDesc indep = d;
    indep.integrator.sampler = SamplerType::Independent;
    const std::string in = (dir_ / "independent.exr").string();
    fs::rename(part(indep, *scene, {4, 8}), in);
    refused({a, in}, {"sampler independent differs", in});
    SceneDesc wide = d;
    wide.sensor.film.width = 30;
    auto wide_scene = Scene::build(wide);
    refused({a, part(wide, *wide_scene, {4, 8})}, {"film 30x18", a});

    // --allow-gaps merges what is there and says what is missing.
    MergeResult m = merge({a, b, c}, true);
    EXPECT_EQ(format_ranges(m.part.ranges), "0:8,10:12");
    EXPECT_EQ(format_ranges(m.gaps), "8:10");
    EXPECT_EQ(m.meta.spp, 10);
    EXPECT_EQ(m.meta.attributes.at("omega.gaps"), "8:10");
}

TEST_F(PartialMerge, APlainRenderIsNotAPart) {
    SceneDesc d = box_scene();
    auto r = test::render(d, 2, 5, 2);
    const std::string plain = (dir_ / "plain.exr").string();
    write_exr(plain, r.film(), ExrMeta{});
    try {
        read_partial_exr(plain);
        ADD_FAILURE() << "read";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("not a partial render"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(plain), std::string::npos) << e.what();
    }
}

TEST(SampleRanges, ParseAndFormat) {
    EXPECT_EQ(parse_sample_range("0:256").end, 256);
    EXPECT_EQ(parse_sample_range("256:512").begin, 256);
    for (const char* bad : {"", "5", "5:5", "6:5", "-1:4", "a:4", "1:4x", ":4", "1:"})
        EXPECT_THROW(parse_sample_range(bad), std::invalid_argument) << bad;
    EXPECT_EQ(format_ranges(parse_ranges("0:8,10:12")), "0:8,10:12");
    EXPECT_THROW(parse_ranges("0:8,4:12"), std::invalid_argument);
    EXPECT_THROW(parse_ranges(""), std::invalid_argument);
}

}  // namespace
}  // namespace omega
