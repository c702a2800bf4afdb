// The samplers: stratification of the Owen-scrambled Sobol' points (elementary intervals of
// every aligned power-of-two range), uniformity and independence of dimensions across pixels
// (chi-square), determinism, and that `independent` is exactly the old PCG stream.
#include "sampling/sampler.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace omega {
namespace {

// Sample `index` of `pixel`, the 2D pair at dimension `dim`.
Vec2 pair_at(uint64_t seed, uint64_t pixel, uint64_t index, uint32_t dim) {
    Sampler s = Sampler::make(SamplerType::Sobol, seed, pixel, index);
    s.start_dimension(dim);
    return s.next_2d();
}

float one_at(uint64_t seed, uint64_t pixel, uint64_t index, uint32_t dim) {
    Sampler s = Sampler::make(SamplerType::Sobol, seed, pixel, index);
    s.start_dimension(dim);
    return s.next_1d();
}

// Every elementary box 2^a x 2^(m-a) holds exactly one of the 2^m points: a (0,m,2)-net.
void expect_net(const std::vector<Vec2>& pts, int m, const std::string& what) {
    ASSERT_EQ(pts.size(), size_t(1) << m);
    for (int a = 0; a <= m; ++a) {
        const int nx = 1 << a, ny = 1 << (m - a);
        std::vector<int> count(size_t(nx) * size_t(ny), 0);
        for (const Vec2& p : pts) {
            ASSERT_TRUE(p.x >= 0.f && p.x < 1.f && p.y >= 0.f && p.y < 1.f) << what;
            int cx = int(p.x * float(nx)), cy = int(p.y * float(ny));
            ++count[size_t(cy) * size_t(nx) + size_t(cx)];
        }
        for (int c : count) ASSERT_EQ(c, 1) << what << ": boxes " << nx << "x" << ny;
    }
}

void expect_strata_1d(const std::vector<float>& xs, const std::string& what) {
    std::vector<int> count(xs.size(), 0);
    for (float x : xs) ++count[size_t(x * float(xs.size()))];
    for (int c : count) ASSERT_EQ(c, 1) << what;
}

const uint32_t kDeepPair = dims::light_walk(40, dims::kScatter) + 1;  // a 2D draw deep in the layout

TEST(SobolSampler, FirstPowerOfTwoSamplesAreNets) {
    for (uint64_t pixel : {0ull, 7ull, 123456ull})
        for (uint32_t dim : {dims::kFilm, dims::kLens, dims::camera_walk(1, dims::kScatter) + 1, kDeepPair}) {
            // Every prefix 2^k of the first 256 samples: progressive, whatever spp turns out to be.
            for (int m = 0; m <= 8; ++m) {
                std::vector<Vec2> pts;
                for (uint64_t i = 0; i < (1u << m); ++i) pts.push_back(pair_at(5, pixel, i, dim));
                expect_net(pts, m, "pixel " + std::to_string(pixel) + " dim " + std::to_string(dim));
            }
        }
}

TEST(SobolSampler, AlignedRangesAreNets) {
    // A part --samples 768:1024 (or a resumed pass) is stratified on its own.
    for (uint32_t dim : {dims::kFilm, kDeepPair})
        for (uint64_t start : {768ull, 4096ull, (1ull << 32) + 256}) {
            std::vector<Vec2> pts;
            for (uint64_t i = start; i < start + 256; ++i) pts.push_back(pair_at(9, 42, i, dim));
            expect_net(pts, 8, "start " + std::to_string(start));
        }
}

TEST(SobolSampler, OneDimensionalDrawsAreStratified) {
    for (uint32_t dim : {dims::camera_walk(1, dims::kDirect), dims::camera_walk(3, dims::kRoulette), dims::kEmit}) {
        std::vector<float> xs;
        for (uint64_t i = 0; i < 1024; ++i) xs.push_back(one_at(3, 11, i, dim));
        expect_strata_1d(xs, "dim " + std::to_string(dim));
        xs.assign(xs.begin() + 512, xs.begin() + 768);
        expect_strata_1d(xs, "dim " + std::to_string(dim) + " samples 512:768");
    }
}

// Chi-square over `bins` equal cells; fixed seeds, so the bound is a regression check, set at
// about 6 standard deviations above the mean (df) of the statistic.
double chi_square(const std::vector<int>& count, double expected) {
    double chi2 = 0;
    for (int c : count) chi2 += (c - expected) * (c - expected) / expected;
    return chi2;
}
double chi_bound(size_t bins) { return double(bins - 1) + 6.0 * std::sqrt(2.0 * double(bins - 1)); }

TEST(SobolSampler, UniformAcrossPixels) {
    // Sample 0 alone of many pixels: the scrambles, not the net, must make it uniform.
    const int pixels = 1 << 14, bins = 256;
    for (uint32_t dim : {dims::kFilm, dims::kLens, kDeepPair, dims::connect_light(3) + 1}) {
        std::vector<int> cx(bins, 0), c2(bins, 0);
        for (int p = 0; p < pixels; ++p) {
            Vec2 u = pair_at(1, uint64_t(p), 0, dim);
            ++cx[size_t(u.x * bins)];
            ++c2[size_t(int(u.x * 16) * 16 + int(u.y * 16))];
        }
        EXPECT_LT(chi_square(cx, double(pixels) / bins), chi_bound(bins)) << "dim " << dim;
        EXPECT_LT(chi_square(c2, double(pixels) / bins), chi_bound(bins)) << "dim " << dim << " (2D)";
    }
}

TEST(SobolSampler, DimensionsAreIndependent) {
    // Pairs of different dimensions of the same sample: 16 x 16 histogram of (a, b) over many
    // pixels and samples. Correlated padding (the same scramble for two dimensions) fails here.
    const int pixels = 1024, spp = 16, bins = 256;
    const std::vector<std::pair<uint32_t, int>> draws = {
        {dims::kFilm, 0}, {dims::kFilm, 1}, {dims::kLens, 0}, {dims::camera_walk(1, dims::kDirect), -1},
        {dims::camera_walk(1, dims::kScatter), -1}, {dims::camera_walk(1, dims::kScatter) + 1, 0},
        {dims::camera_walk(2, dims::kScatter) + 1, 0}, {dims::kEmit, -1}};
    auto value = [](uint64_t pixel, uint64_t i, std::pair<uint32_t, int> d) {
        if (d.second < 0) return one_at(2, pixel, i, d.first);
        Vec2 u = pair_at(2, pixel, i, d.first);
        return d.second == 0 ? u.x : u.y;
    };
    for (size_t a = 0; a < draws.size(); ++a)
        for (size_t b = a + 1; b < draws.size(); ++b) {
            std::vector<int> count(bins, 0);
            for (int p = 0; p < pixels; ++p)
                for (int i = 0; i < spp; ++i) {
                    float x = value(uint64_t(p), uint64_t(i), draws[a]), y = value(uint64_t(p), uint64_t(i), draws[b]);
                    ++count[size_t(int(x * 16) * 16 + int(y * 16))];
                }
            EXPECT_LT(chi_square(count, double(pixels * spp) / bins), chi_bound(bins)) << "draws " << a << ", " << b;
        }
}

TEST(SobolSampler, FastPathEqualsThePlainFormulas) {
    // next_1d/next_2d cancel bit reversals and use a table for dimension 1; the plain
    // composition i' = owen(i), x = owen(dim0(i')), y = owen(dim1(i')) must give the same bits.
    for (uint32_t i = 0; i < 4096; i += 7) EXPECT_EQ(sobol::dim1(i * 2654435761u), sobol::dim1_by_bits(i * 2654435761u));
    for (uint32_t z = 0; z < 1u << 20; z += 97) {
        const uint32_t w = z * 2654435761u;
        const uint64_t u = sobol::unshuffle(w);
        EXPECT_EQ(uint32_t(u), sobol::reverse_bits(w)) << w;
        EXPECT_EQ(uint32_t(u >> 32), sobol::dim1_reversed(sobol::reverse_bits(w))) << w;
    }
    for (uint64_t x : {0ull, 1ull, 0x8000000000000001ull, 0x0123456789abcdefull, ~0ull, 0xdeadbeef00c0ffeeull}) {
        const uint64_t r = sobol::reverse_bits_halves(x);
        EXPECT_EQ(uint32_t(r), sobol::reverse_bits(uint32_t(x))) << x;
        EXPECT_EQ(uint32_t(r >> 32), sobol::reverse_bits(uint32_t(x >> 32))) << x;
    }
    for (uint64_t index : {0ull, 1ull, 77ull, 1000003ull, (1ull << 32) + 5})
        for (uint32_t dim : {dims::kFilm, dims::kLens, kDeepPair}) {
            const uint64_t h = mix64(hash3(8, 21, index >> 32) ^ (uint64_t(dim) * 0x9e3779b97f4a7c15ULL));
            const uint32_t c = uint32_t(((h ^ (h >> 29)) * 0xbf58476d1ce4e5b9ULL) >> 32);
            const uint32_t i = sobol::owen(uint32_t(index), uint32_t(h));
            Vec2 u = pair_at(8, 21, index, dim);
            EXPECT_EQ(u.x, sobol::to_unit(sobol::owen(sobol::dim0(i), uint32_t(h >> 32))));
            EXPECT_EQ(u.y, sobol::to_unit(sobol::owen(sobol::dim1(i), c)));
            EXPECT_EQ(one_at(8, 21, index, dim), u.x);  // a 1D draw is the pair's first coordinate
        }
}

TEST(SobolSampler, Deterministic) {
    // A value depends only on (seed, pixel, index, dimension): not on the draws before it.
    Sampler s = Sampler::make(SamplerType::Sobol, 4, 99, 17);
    s.start_dimension(dims::kFilm);
    Vec2 film = s.next_2d();
    s.start_dimension(dims::camera_walk(2, dims::kScatter));
    float lobe = s.next_1d();
    Vec2 dir = s.next_2d();
    Sampler t = Sampler::make(SamplerType::Sobol, 4, 99, 17);
    t.start_dimension(dims::camera_walk(2, dims::kScatter));
    EXPECT_EQ(t.next_1d(), lobe);
    EXPECT_EQ(t.next_2d().x, dir.x);
    EXPECT_EQ(pair_at(4, 99, 17, dims::kFilm).x, film.x);
    EXPECT_EQ(pair_at(4, 99, 17, dims::kFilm).y, film.y);
    EXPECT_NE(pair_at(5, 99, 17, dims::kFilm).x, film.x);  // the seed matters
    EXPECT_NE(pair_at(4, 98, 17, dims::kFilm).x, film.x);  // so does the pixel
}

TEST(SobolSampler, BeyondTheLayoutDrawsIndependentNumbers) {
    EXPECT_EQ(dims::camera_walk(dims::kMaxDepth, dims::kScatter), dims::kBeyond);
    EXPECT_EQ(dims::connect_sensor(-1), dims::kBeyond);
    std::vector<int> count(64, 0);
    for (uint64_t i = 0; i < 64 * 256; ++i) {
        Sampler s = Sampler::make(SamplerType::Sobol, 1, 3, i);
        s.start_dimension(dims::kBeyond);
        float u = s.next_1d();
        ASSERT_TRUE(u >= 0.f && u < 1.f);
        ++count[size_t(u * 64)];
    }
    EXPECT_LT(chi_square(count, 256.0), chi_bound(64));
}

TEST(SobolSampler, BeyondTheLayoutIsItsOwnPcgStreamWhereverItStarts) {
    // The stream is seeded on the first draw past the layout: it must be the same stream, in
    // call order, whether that draw comes first, after draws in the layout, or in a copy.
    for (uint64_t index : {0ull, 5ull, (1ull << 32) + 9}) {
        Rng ref = Rng::for_sample(6 ^ 0x50b01f5eedULL, 42, index);
        const float r0 = ref.next_1d(), r1 = ref.next_1d(), r2 = ref.next_1d(), r3 = ref.next_1d();
        Sampler a = Sampler::make(SamplerType::Sobol, 6, 42, index);
        a.start_dimension(dims::kBeyond);
        EXPECT_EQ(a.next_1d(), r0);
        const Vec2 u = a.next_2d();
        EXPECT_EQ(u.x, r1);
        EXPECT_EQ(u.y, r2);
        Sampler b = Sampler::make(SamplerType::Sobol, 6, 42, index);
        b.start_dimension(dims::kFilm);
        const Vec2 film = b.next_2d();
        b.start_dimension(dims::kBeyond);
        Sampler copy = b;  // not yet seeded: the copy seeds its own, the same
        b.skip_1d();
        EXPECT_EQ(b.next_1d(), r1);
        EXPECT_EQ(copy.next_1d(), r0);
        b.start_dimension(dims::kFilm);
        EXPECT_EQ(b.next_2d().x, film.x);  // the layout's draws do not depend on the stream
        b.start_dimension(dims::kBeyond);
        EXPECT_EQ(b.next_1d(), r2);  // and the stream goes on where it was
        EXPECT_EQ(b.next_1d(), r3);
    }
}

TEST(IndependentSampler, IsTheOldPcgStream) {
    // --sampler independent must reproduce images made before the sampler existed, bit for bit.
    for (uint64_t i : {0ull, 5ull, 1000ull}) {
        Rng rng = Rng::for_sample(7, 12, i);
        Sampler s = Sampler::make(SamplerType::Independent, 7, 12, i);
        s.start_dimension(dims::kLens);  // ignored
        EXPECT_EQ(s.next_1d(), rng.next_1d());
        Vec2 u = s.next_2d();
        EXPECT_EQ(u.x, rng.next_1d());
        EXPECT_EQ(u.y, rng.next_1d());
    }
}

// A skipped decision must leave every later draw as a drawn one would: integrators skip the
// draws a scene cannot need (one light, one lobe), and images must not change with that.
TEST(Sampler, SkippingADrawLeavesTheLaterDrawsAsTheyWere) {
    for (SamplerType type : {SamplerType::Sobol, SamplerType::Independent})
        for (uint32_t dim : {dims::camera_walk(2, dims::kDirect), dims::kBeyond})
            for (uint64_t index : {0ull, 5ull, 1ull << 33}) {
                Sampler drawn = Sampler::make(type, 3, 77, index), skipped = drawn;
                drawn.start_dimension(dim);
                skipped.start_dimension(dim);
                (void)drawn.next_1d();
                EXPECT_EQ(skipped.next_1d_if(false), 0.f);
                const Vec2 a = drawn.next_2d(), b = skipped.next_2d();
                EXPECT_EQ(a.x, b.x);
                EXPECT_EQ(a.y, b.y);
                EXPECT_EQ(drawn.next_1d(), skipped.next_1d());
                // And a needed one is the plain draw.
                Sampler c = Sampler::make(type, 3, 77, index), d = c;
                c.start_dimension(dim);
                d.start_dimension(dim);
                EXPECT_EQ(c.next_1d(), d.next_1d_if(true));
            }
}

// The integrators compute a sobol vertex's 2D draws before tracing its ray (sobol_2d_at) and then
// skip them in the stream: the values, and every later draw, must be those of the plain order.
TEST(SobolSampler, DrawAheadIsTheDrawInOrder) {
    EXPECT_TRUE(Sampler::make(SamplerType::Sobol, 1, 2, 3).order_free());
    EXPECT_FALSE(Sampler::make(SamplerType::Independent, 1, 2, 3).order_free());
    for (uint32_t dim : {dims::kFilm, dims::camera_walk(1, dims::kScatter + 1), dims::light_walk(63, dims::kScatter + 1)})
        for (uint64_t index : {0ull, 5ull, 1ull << 33}) {
            Sampler in_order = Sampler::make(SamplerType::Sobol, 3, 77, index), ahead = in_order;
            const Vec2 early = ahead.sobol_2d_at(dim);
            in_order.start_dimension(dim);
            ahead.start_dimension(dim);
            const Vec2 plain = in_order.next_2d(), taken = ahead.next_2d(&early);
            EXPECT_EQ(early.x, plain.x);
            EXPECT_EQ(early.y, plain.y);
            EXPECT_EQ(taken.x, plain.x);
            EXPECT_EQ(in_order.next_1d(), ahead.next_1d());
        }
}

TEST(SamplerType, Names) {
    EXPECT_STREQ(sampler_name(SamplerType::Sobol), "sobol");
    EXPECT_EQ(sampler_from_name("independent"), SamplerType::Independent);
    EXPECT_FALSE(sampler_from_name("halton").has_value());
}

}  // namespace
}  // namespace omega
