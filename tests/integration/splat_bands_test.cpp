// The parallel splat merge must give every pixel exactly the sums of the serial merge (the
// same additions in the same order), for any band height, filter and thread count: light
// tracing's and BDPT's images are bit-identical across thread counts only if it does.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "integrator/splat_bands.h"
#include "sampling/rng.h"

namespace omega {
namespace {

std::vector<std::vector<Splat>> random_splats(const Rect& crop, uint64_t seed) {
    Rng rng = Rng::for_sample(seed, 0, 0);
    std::vector<std::vector<Splat>> tiles(7);
    for (auto& t : tiles)
        for (int i = 0; i < 300; ++i) {
            Splat s;
            // Some land outside the crop, some exactly on pixel borders.
            s.film = {float(crop.x0) - 2.f + rng.next_1d() * float(crop.width() + 4),
                      float(crop.y0) - 2.f + rng.next_1d() * float(crop.height() + 4)};
            if (i % 17 == 0) s.film.y = std::floor(s.film.y);
            s.value = Rgb(rng.next_1d(), rng.next_1d() * 10.f, 1e-3f + rng.next_1d());
            t.push_back(s);
        }
    return tiles;
}

TEST(SplatBands, ParallelMergeIsBitIdenticalToTheSerialOne) {
    const Rect crop{3, 5, 40, 34};
    const auto tiles = random_splats(crop, 11);
    auto at = [&](int x, int y) { return size_t(y - crop.y0) * size_t(crop.width()) + size_t(x - crop.x0); };
    for (FilterType type : {FilterType::Box, FilterType::Tent, FilterType::Gaussian}) {
        const Filter filter(type, type == FilterType::Box ? 0.5f : 1.5f);
        std::vector<Vec3d> serial(size_t(crop.area()), Vec3d(0.0));
        for (const auto& list : tiles)
            for (const Splat& sp : list)
                for_each_filter_pixel(filter, crop, sp.film,
                                      [&](int x, int y, double f) { serial[at(x, y)] += Vec3d(sp.value) * f; });
        for (int threads : {1, 2, 3})
            for (int rows : {1, 3, 8, 64}) {
                tbb::task_arena arena(threads);
                SplatBands bands(crop, filter.radius(), rows);
                // Bucketed as the workers do, one tile at a time, into lists reused from a
                // larger earlier batch (stale capacity must not leak into the sums).
                std::vector<BandedSplats> bucketed(tiles.size());
                for (size_t t = 0; t < tiles.size(); ++t) bands.bucket(tiles[(t + 3) % tiles.size()], bucketed[t]);
                for (size_t t = 0; t < tiles.size(); ++t) bands.bucket(tiles[t], bucketed[t]);
                bucketed.emplace_back();  // a tile that did not run: no lists, nothing merged
                std::vector<Vec3d> banded(size_t(crop.area()), Vec3d(0.0));
                bands.merge(arena, filter, bucketed,
                            [&](const Splat& sp, int x, int y, double f) { banded[at(x, y)] += Vec3d(sp.value) * f; });
                ASSERT_EQ(0, std::memcmp(serial.data(), banded.data(), serial.size() * sizeof(Vec3d)))
                    << "filter " << int(type) << " threads " << threads << " band rows " << rows;
            }
        double total = 0;
        for (const Vec3d& v : serial) total += v.x;
        EXPECT_GT(total, 0.0);
    }
}

TEST(SplatBands, BandsCoverTheCropOnce) {
    const Rect crop{0, 2, 10, 23};
    SplatBands bands(crop, 1.f, 8);
    ASSERT_EQ(bands.bands(), 3u);
    int rows = 0;
    for (size_t b = 0; b < bands.bands(); ++b) {
        const Rect r = bands.band(b);
        EXPECT_EQ(r.y0, crop.y0 + rows);
        EXPECT_EQ(r.x0, crop.x0);
        EXPECT_EQ(r.x1, crop.x1);
        rows += r.height();
    }
    EXPECT_EQ(rows, crop.height());
}


// The bands a layout cuts the crop into: contiguous, in order, full width, each inside one base
// band of `rows` rows.
void expect_cover(const SplatBands& bands, const Rect& crop, int rows) {
    int y = crop.y0;
    for (size_t b = 0; b < bands.bands(); ++b) {
        const Rect r = bands.band(b);
        EXPECT_EQ(r.y0, y) << "band " << b;
        EXPECT_GT(r.y1, r.y0) << "band " << b;
        EXPECT_EQ(r.x0, crop.x0);
        EXPECT_EQ(r.x1, crop.x1);
        EXPECT_EQ((r.y0 - crop.y0) / rows, (r.y1 - 1 - crop.y0) / rows) << "band " << b << " crosses a base band";
        y = r.y1;
    }
    EXPECT_EQ(y, crop.y1);
}

TEST(SplatBands, HeavyBandsAreCutPerWorkerAndTheMergeStaysBitIdentical) {
    // Half the splats on rows 17-19 (the light in view), the rest anywhere.
    const Rect crop{2, 1, 50, 49};
    constexpr int kRows = 8;
    auto tiles = random_splats(crop, 5);
    Rng rng = Rng::for_sample(9, 0, 0);
    for (auto& t : tiles)
        for (size_t i = 0; i < t.size(); i += 2) t[i].film.y = 17.f + 3.f * rng.next_1d();
    const Filter filter(FilterType::Tent, 1.f);
    auto at = [&](int x, int y) { return size_t(y - crop.y0) * size_t(crop.width()) + size_t(x - crop.x0); };
    std::vector<Vec3d> serial(size_t(crop.area()), Vec3d(0.0));
    for (const auto& list : tiles)
        for (const Splat& sp : list)
            for_each_filter_pixel(filter, crop, sp.film, [&](int x, int y, double f) { serial[at(x, y)] += Vec3d(sp.value) * f; });
    // What a merge on `bands` counts, per base band: each splat once per band its footprint
    // reaches.
    const size_t base = size_t(crop.height() + kRows - 1) / kRows;
    auto counted = [&](const SplatBands& bands) {
        std::vector<uint64_t> count(base, 0);
        uint64_t total = 0;
        for (const auto& list : tiles)
            for (const Splat& sp : list) {
                const auto [ya, yb] = filter_span(sp.film.y, filter.radius(), crop.y0, crop.y1);
                for (size_t b = 0; b < bands.bands(); ++b) {
                    const Rect r = bands.band(b);
                    if (r.y0 > yb || r.y1 <= ya) continue;
                    ++count[size_t(r.y0 - crop.y0) / kRows];
                    ++total;
                }
            }
        return std::pair{count, total};
    };
    tbb::task_arena arena(3);
    auto merge_matches = [&](SplatBands& bands) {
        std::vector<BandedSplats> bucketed(tiles.size());
        for (size_t t = 0; t < tiles.size(); ++t) bands.bucket(tiles[t], bucketed[t]);
        std::vector<Vec3d> banded(size_t(crop.area()), Vec3d(0.0));
        bands.merge(arena, filter, bucketed,
                    [&](const Splat& sp, int x, int y, double f) { banded[at(x, y)] += Vec3d(sp.value) * f; });
        return std::memcmp(serial.data(), banded.data(), serial.size() * sizeof(Vec3d)) == 0;
    };
    for (int workers : {1, 2, 4, 16}) {
        SCOPED_TRACE(workers);
        SplatBands bands(crop, filter.radius(), kRows);
        // Nothing merged yet: the base cut stays where no band would be cut for lack of
        // workers, and beyond 2 workers every band is one row.
        bands.relayout(workers);
        ASSERT_EQ(bands.bands(), workers > 2 ? size_t(crop.height()) : base);
        expect_cover(bands, crop, kRows);
        ASSERT_TRUE(merge_matches(bands));
        const auto [count, total] = counted(bands);
        bands.relayout(workers);
        expect_cover(bands, crop, kRows);
        // Each base band in ceil(share * workers) parts, at most one a row.
        std::vector<uint64_t> parts(base, 0);
        for (size_t b = 0; b < bands.bands(); ++b) ++parts[size_t(bands.band(b).y0 - crop.y0) / kRows];
        for (size_t k = 0; k < base; ++k) {
            const int rows = std::min(kRows, crop.y1 - (crop.y0 + int(k) * kRows));
            const uint64_t want = std::clamp<uint64_t>((count[k] * uint64_t(workers) + total - 1) / total, 1, uint64_t(rows));
            EXPECT_EQ(parts[k], want) << "base band " << k;
        }
        if (workers == 2) {
            EXPECT_EQ(bands.bands(), base + 1);  // only the heavy band, in two
        }
        if (workers == 16) {
            EXPECT_EQ(parts[2], 8u);  // the heavy band, a row each
        }
        // The next batch, on the new cut: the same sums, bit for bit.
        EXPECT_TRUE(merge_matches(bands));
        bands.relayout(workers);
        expect_cover(bands, crop, kRows);
        EXPECT_TRUE(merge_matches(bands));
    }
}

}  // namespace
}  // namespace omega
