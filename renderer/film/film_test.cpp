#include "film/film.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <thread>

#include "film/test_util.h"
#include "sampling/rng.h"

namespace omega {
namespace {

FilmDesc desc(int w, int h) {
    FilmDesc d;
    d.width = w;
    d.height = h;
    return d;
}

using test::cropped;

// Two-pass mean and unbiased sample variance in long double, the reference for Welford.
void two_pass(const std::vector<double>& v, long double& mean, long double& var) {
    mean = 0;
    for (double x : v) mean += x;
    mean /= v.size();
    long double ss = 0;
    for (double x : v) ss += (x - mean) * (x - mean);
    var = ss / (v.size() - 1);
}

TEST(Film, CropDefaultsToWholeFilmAndValidates) {
    Film f(desc(7, 5));
    EXPECT_EQ(f.width(), 7);
    EXPECT_EQ(f.height(), 5);
    EXPECT_EQ(f.crop().x1, 7);
    EXPECT_EQ(f.crop().area(), 35);
    Film c(cropped(7, 5, 1, 2, 6, 5));
    EXPECT_EQ(c.crop().x0, 1);
    EXPECT_EQ(c.crop().area(), 15);
    EXPECT_THROW(Film(cropped(7, 5, 1, 2, 8, 5)), std::invalid_argument);
    EXPECT_THROW(Film(cropped(7, 5, 3, 2, 3, 5)), std::invalid_argument);
    EXPECT_THROW(Film(desc(0, 5)), std::invalid_argument);
    EXPECT_THROW(c.add_sample(0, 2, Rgb(1.f)), std::out_of_range);
    EXPECT_THROW(c.pixel(6, 4), std::out_of_range);
}

TEST(Film, TilesCoverCropOnceInRowMajorOrder) {
    Film f(cropped(37, 29, 3, 5, 36, 28));
    const auto tiles = f.tiles(8);
    ASSERT_EQ(tiles.size(), 5u * 3u);
    std::vector<int> cover(37 * 29, 0);
    for (size_t i = 0; i < tiles.size(); ++i) {
        const Rect& t = tiles[i];
        EXPECT_GT(t.area(), 0);
        EXPECT_LE(t.width(), 8);
        if (i > 0) {
            const Rect& p = tiles[i - 1];
            EXPECT_TRUE(t.y0 > p.y0 || (t.y0 == p.y0 && t.x0 > p.x0)) << "not row-major at " << i;
        }
        for (int y = t.y0; y < t.y1; ++y)
            for (int x = t.x0; x < t.x1; ++x) cover[y * 37 + x]++;
    }
    for (int y = 0; y < 29; ++y)
        for (int x = 0; x < 37; ++x) {
            const bool inside = x >= 3 && x < 36 && y >= 5 && y < 28;
            EXPECT_EQ(cover[y * 37 + x], inside ? 1 : 0) << x << "," << y;
        }
    EXPECT_EQ(f.tiles(1000).size(), 1u);
    EXPECT_THROW(f.tiles(0), std::invalid_argument);
}

TEST(Film, WelfordMatchesTwoPassInLongDouble) {
    Film f(desc(3, 1));
    Rng rng(42, 0);
    std::vector<double> vals[3][3];
    // Pixel 2 rides on a large offset: naive sum-of-squares would lose the variance entirely.
    const float offsets[3] = {0.f, 1.f, 1e4f};
    const int counts[3] = {2, 1000, 20000};
    for (int px = 0; px < 3; ++px)
        for (int i = 0; i < counts[px]; ++i) {
            Rgb v(offsets[px] + rng.next_1d(), offsets[px] + 2.f * rng.next_1d(), offsets[px] + rng.next_1d() * rng.next_1d());
            for (int c = 0; c < 3; ++c) vals[px][c].push_back(v[c]);
            f.add_sample(px, 0, v);
        }
    for (int px = 0; px < 3; ++px) {
        const PixelStats s = f.pixel(px, 0);
        EXPECT_EQ(s.n, uint64_t(counts[px]));
        for (int c = 0; c < 3; ++c) {
            long double m, v;
            two_pass(vals[px][c], m, v);
            const long double vom = v / counts[px];
            EXPECT_NEAR(s.mean[c], double(m), 1e-12 * std::max(1.0, std::abs(double(m))));
            EXPECT_NEAR(s.var_of_mean[c], double(vom), 1e-9 * double(vom)) << px << " " << c;
        }
    }
}

TEST(Film, FewerThanTwoSamplesHaveZeroVariance) {
    Film f(desc(2, 1));
    EXPECT_EQ(f.pixel(0, 0).n, 0u);
    f.add_sample(0, 0, Rgb(3.f, 4.f, 5.f));
    const PixelStats s = f.pixel(0, 0);
    EXPECT_EQ(s.n, 1u);
    EXPECT_EQ(s.mean, Vec3d(3, 4, 5));
    EXPECT_EQ(s.var_of_mean, Vec3d(0, 0, 0));
    f.clear();
    EXPECT_EQ(f.pixel(0, 0).n, 0u);
    EXPECT_EQ(f.pixel(0, 0).mean, Vec3d(0, 0, 0));
}

void fill(Film& f, uint64_t seed, int max_n) {
    const Rect c = f.crop();
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            Rng rng = Rng::for_sample(seed, uint64_t(y * 1000 + x), 0);
            const int n = int(rng.next_u32() % uint32_t(max_n + 1));  // includes empty pixels
            for (int i = 0; i < n; ++i)
                f.add_sample(x, y, Rgb(rng.next_1d() * 5.f, float(x), rng.next_1d() < 0.1f ? 100.f : 0.f));
        }
}

TEST(Film, MergeEqualsSequentialAccumulation) {
    const FilmDesc d = cropped(9, 7, 1, 1, 8, 6);
    Film a(d), b(d), seq(d);
    fill(a, 1, 30);
    fill(b, 2, 30);
    fill(seq, 1, 30);
    fill(seq, 2, 30);
    a.merge(b);
    for (int y = 1; y < 6; ++y)
        for (int x = 1; x < 8; ++x) {
            const PixelStats m = a.pixel(x, y), s = seq.pixel(x, y);
            ASSERT_EQ(m.n, s.n);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(m.mean[c], s.mean[c], 1e-12 * std::max(1.0, std::abs(s.mean[c])));
                EXPECT_NEAR(m.var_of_mean[c], s.var_of_mean[c], 1e-10 * std::max(1e-12, s.var_of_mean[c]));
            }
        }
    // Merging into or from an empty film is exact.
    Film empty(d), copy(d);
    copy.merge(seq);
    copy.merge(empty);
    EXPECT_EQ(copy.serialize(), seq.serialize());
    EXPECT_THROW(a.merge(Film(desc(9, 7))), std::invalid_argument);
}

TEST(Film, SerializeRoundTripIsExact) {
    const FilmDesc d = cropped(11, 6, 2, 1, 10, 6);
    Film f(d);
    fill(f, 5, 10);
    const auto bytes = f.serialize();
    const Film g = Film::deserialize(d, bytes);
    EXPECT_EQ(g.serialize(), bytes);
    for (int y = 1; y < 6; ++y)
        for (int x = 2; x < 10; ++x) {
            const PixelStats a = f.pixel(x, y), b = g.pixel(x, y);
            EXPECT_EQ(a.n, b.n);
            EXPECT_EQ(a.mean, b.mean);
            EXPECT_EQ(a.var_of_mean, b.var_of_mean);
        }
}

TEST(Film, DeserializeRejectsCorruption) {
    const FilmDesc d = cropped(11, 6, 2, 1, 10, 6);
    Film f(d);
    fill(f, 5, 10);
    const auto good = f.serialize();
    auto expect_reject = [&](std::vector<uint8_t> bytes, const FilmDesc& dd, const char* what) {
        EXPECT_THROW(Film::deserialize(dd, bytes), std::runtime_error) << what;
    };
    expect_reject({}, d, "empty");
    for (size_t len : {size_t(4), size_t(40), good.size() / 2, good.size() - 1})
        expect_reject(std::vector<uint8_t>(good.begin(), good.begin() + long(len)), d, "truncated");
    auto longer = good;
    longer.push_back(0);
    expect_reject(longer, d, "trailing byte");
    // A flipped bit anywhere, header, pixel or checksum, is caught.
    for (size_t i = 0; i < good.size(); i += 7) {
        auto bad = good;
        bad[i] ^= 0x10;
        expect_reject(bad, d, "bit flip");
    }
    expect_reject(good, cropped(11, 6, 2, 1, 10, 5), "other crop");
    expect_reject(good, desc(11, 6), "other size");
    Rng rng(9, 9);
    std::vector<uint8_t> garbage(good.size());
    for (auto& b : garbage) b = uint8_t(rng.next_u32());
    expect_reject(garbage, d, "garbage");
}

TEST(Film, EstimateErrorOnSyntheticFilm) {
    // 2x1 film. Pixel 0: samples {1, 3} in every channel: mean 2, M2 2, var of mean 2/(2*1) = 1.
    // Pixel 1: R {0, 0, 0}, G {3, 3, 3}, B {0, 6, 0}: means (0, 3, 2), channel mean 5/3;
    // M2 of B = 24, var of mean 24/(3*2) = 4, channel-average var 4/3.
    Film f(desc(2, 1));
    f.add_sample(0, 0, Rgb(1.f));
    f.add_sample(0, 0, Rgb(3.f));
    f.add_sample(1, 0, Rgb(0.f, 3.f, 0.f));
    f.add_sample(1, 0, Rgb(0.f, 3.f, 6.f));
    f.add_sample(1, 0, Rgb(0.f, 3.f, 0.f));
    const ErrorEstimate e = f.estimate_error(1e-2);
    const double rel0 = 1.0 / 2.0, rel1 = std::sqrt(4.0 / 3.0) / (5.0 / 3.0);
    EXPECT_NEAR(e.mean_rel_error, (rel0 + rel1) / 2, 1e-12);
    EXPECT_NEAR(e.image_mean, (2.0 + 5.0 / 3.0) / 2, 1e-12);
    EXPECT_NEAR(e.image_mean_stderr, std::sqrt(1.0 + 4.0 / 3.0) / 2, 1e-12);

    // eps guards dark pixels: mean 0 and var of mean 1 give 1/eps.
    Film dark(desc(1, 1));
    dark.add_sample(0, 0, Rgb(-1.f));
    dark.add_sample(0, 0, Rgb(1.f));
    EXPECT_NEAR(dark.estimate_error(0.5).mean_rel_error, 2.0, 1e-12);

    // Until every pixel has two samples the error is unknown, never optimistic.
    Film partial(desc(2, 1));
    partial.add_sample(0, 0, Rgb(1.f));
    partial.add_sample(0, 0, Rgb(1.f));
    partial.add_sample(1, 0, Rgb(1.f));
    EXPECT_TRUE(std::isinf(partial.estimate_error().mean_rel_error));
    EXPECT_TRUE(std::isinf(partial.estimate_error().image_mean_stderr));
    EXPECT_TRUE(std::isinf(Film(desc(2, 2)).estimate_error().mean_rel_error));
}

TEST(Film, EstimateErrorTracksTrueError) {
    // Constant-mean noise: the standard error must shrink like 1/sqrt(n) and be about right.
    Film f(desc(16, 16));
    const int n = 400;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            Rng rng = Rng::for_sample(3, uint64_t(y * 16 + x), 0);
            for (int i = 0; i < n; ++i) f.add_sample(x, y, Rgb(2.f * rng.next_1d()));  // mean 1, var 1/3
        }
    const ErrorEstimate e = f.estimate_error();
    const double sd_mean = std::sqrt(1.0 / 3.0 / n);
    EXPECT_NEAR(e.mean_rel_error, sd_mean, 0.05 * sd_mean);
    EXPECT_NEAR(e.image_mean_stderr, sd_mean / 16, 0.05 * sd_mean / 16);
    EXPECT_NEAR(e.image_mean, 1.0, 5 * sd_mean / 16);
}

TEST(Film, ErrorInChunksIsTheErrorWhateverOrderTheChunksRan) {
    // 12 chunks and a part, with one pixel of fewer than two samples in the last chunk only.
    const int w = 301, h = 170;
    Film f(desc(w, h));
    ASSERT_EQ(f.error_parts(), 13u);
    double rel = 0, mean = 0, var = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            Rng rng = Rng::for_sample(5, uint64_t(y * w + x), 0);
            const float a = 1.f + rng.next_1d(), b = rng.next_1d();
            f.add_sample(x, y, Rgb(a));
            f.add_sample(x, y, Rgb(b));
            const double m = (double(a) + double(b)) / 2, v = (double(a) - double(b)) * (double(a) - double(b)) / 2;
            mean += m;
            var += v / 2;
            rel += std::sqrt(v / 2) / std::max(m, 1e-2);
        }
    const double N = double(w) * h;
    const ErrorEstimate e = f.estimate_error();
    EXPECT_NEAR(e.mean_rel_error, rel / N, 1e-12 * rel / N);
    EXPECT_NEAR(e.image_mean, mean / N, 1e-12 * mean / N);
    EXPECT_NEAR(e.image_mean_stderr, std::sqrt(var) / N, 1e-12 * std::sqrt(var) / N);
    // The chunks computed last to first (as workers might) add up to the same bits.
    std::vector<Film::ErrorPart> parts(f.error_parts());
    for (size_t c = parts.size(); c-- > 0;) parts[c] = f.error_part(c);
    const ErrorEstimate g = f.error_of(parts);
    EXPECT_EQ(std::memcmp(&e, &g, sizeof e), 0);
    // A pixel with one sample, in the last chunk alone, still makes the error unknown.
    f.set_state(w - 1, h - 1, PixelState{});
    f.add_sample(w - 1, h - 1, Rgb(1.f));
    EXPECT_TRUE(std::isinf(f.estimate_error().mean_rel_error));
}

TEST(Film, ConcurrentWritersOnSeparateTiles) {
    // Each worker owns a tile, as the renderer guarantees; the result must equal a serial run.
    const FilmDesc d = desc(40, 24);
    Film par(d), ser(d);
    const auto tiles = par.tiles(8);
    auto render = [&](Film& f, const Rect& t) {
        for (int y = t.y0; y < t.y1; ++y)
            for (int x = t.x0; x < t.x1; ++x)
                for (int i = 0; i < 50; ++i) {
                    Rng rng = Rng::for_sample(11, uint64_t(y * 40 + x), uint64_t(i));
                    f.add_sample(x, y, Rgb(rng.next_1d(), rng.next_1d(), rng.next_1d()));
                }
    };
    std::vector<std::thread> workers;
    for (int w = 0; w < 4; ++w)
        workers.emplace_back([&, w] {
            for (size_t i = size_t(w); i < tiles.size(); i += 4) render(par, tiles[i]);
        });
    for (auto& t : workers) t.join();
    for (const Rect& t : tiles) render(ser, t);
    EXPECT_EQ(par.serialize(), ser.serialize());
}

}  // namespace
}  // namespace omega

namespace omega {
namespace {

// A part's state channels come from a file: set_state takes back exactly what state() gave, and
// refuses what no film could hold (a hostile or corrupt part must not poison a merge).
TEST(Film, StateRoundTripsAndRefusesImpossibleStates) {
    FilmDesc d;
    d.width = 3;
    d.height = 2;
    Film a(d), b(d);
    a.add_sample(1, 1, Rgb(0.25f, 2.f, 7.f));
    a.add_sample(1, 1, Rgb(0.5f, 1.f, 3.f));
    b.set_state(1, 1, a.state(1, 1));
    const PixelState sa = a.state(1, 1), sb = b.state(1, 1);
    EXPECT_EQ(std::memcmp(&sa, &sb, sizeof(PixelState)), 0);
    EXPECT_EQ(b.pixel(1, 1).var_of_mean.x, a.pixel(1, 1).var_of_mean.x);
    PixelState s = a.state(1, 1);
    auto refuses = [&](PixelState bad) { EXPECT_THROW(b.set_state(0, 0, bad), std::runtime_error); };
    PixelState nan_mean = s;
    nan_mean.mean[1] = std::nan("");
    refuses(nan_mean);
    PixelState negative_m2 = s;
    negative_m2.m2[2] = -1;
    refuses(negative_m2);
    PixelState weight_without_samples = s;
    weight_without_samples.n = 0;
    refuses(weight_without_samples);
    PixelState empty_with_mean{};
    empty_with_mean.mean[0] = 1;
    refuses(empty_with_mean);
    EXPECT_THROW(b.set_state(3, 0, s), std::out_of_range);
    EXPECT_EQ(b.pixel(0, 0).n, 0u);  // nothing refused was written
}

}  // namespace
}  // namespace omega
