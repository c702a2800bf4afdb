// ZeroedArray (film/zeroed_array.h) and the film built on it: zero-filled, cache-line aligned,
// copies and moves that own their bytes, and a large film whose construction touches none of its
// pages (its first tile waited for every page of the film to fault in before).
#include "film/zeroed_array.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <unistd.h>

#include "film/film.h"
#include "math/vec.h"

namespace omega {
namespace {

struct alignas(64) Line {
    double v[7];
    uint64_t n;
};

TEST(ZeroedArray, ZeroFilledAndAligned) {
    for (size_t n : {size_t(1), size_t(3), size_t(1000), size_t(100000)}) {
        ZeroedArray<Line> a(n);
        ASSERT_EQ(a.size(), n);
        EXPECT_EQ(reinterpret_cast<uintptr_t>(a.data()) % 64, 0u) << n;
        for (const Line& l : a) {
            EXPECT_EQ(l.n, 0u);
            for (double x : l.v) EXPECT_EQ(x, 0.0);
        }
        EXPECT_EQ(a.end() - a.begin(), ptrdiff_t(n));
    }
    ZeroedArray<Line> empty(0);
    EXPECT_TRUE(empty.empty());
    EXPECT_EQ(empty.begin(), empty.end());
}

// A block of 2 MB or more starts on a 2 MB boundary, so all its whole 2 MB pages can be huge
// pages; a smaller one keeps the type's alignment only. Vec3d (default member initialisers, so
// not trivially default-constructible) is held as its zero bytes.
TEST(ZeroedArray, LargeBlocksStartOnAHugePage) {
    constexpr uintptr_t kHuge = uintptr_t(2) << 20;
    for (size_t n : {kHuge / sizeof(Line), size_t(65536), size_t(1) << 20}) {
        ZeroedArray<Line> a(n);
        EXPECT_EQ(reinterpret_cast<uintptr_t>(a.data()) % kHuge, 0u) << n << " lines";
        EXPECT_EQ(a[n - 1].n, 0u);
    }
    ZeroedArray<Vec3d> v(256 * 256);  // 1.5 MB: below the threshold
    EXPECT_EQ(reinterpret_cast<uintptr_t>(v.data()) % alignof(Vec3d), 0u);
    ZeroedArray<Vec3d> w(1024 * 1024);  // 24 MB
    EXPECT_EQ(reinterpret_cast<uintptr_t>(w.data()) % kHuge, 0u);
    for (size_t i : {size_t(0), size_t(12345), w.size() - 1}) {
        EXPECT_EQ(w[i].x, 0.0);
        EXPECT_EQ(w[i].y, 0.0);
        EXPECT_EQ(w[i].z, 0.0);
    }
}

TEST(ZeroedArray, CopiesAndMovesOwnTheirBytes) {
    ZeroedArray<Line> a(5);
    a[2].n = 7;
    a[4].v[6] = 1.5;
    ZeroedArray<Line> b = a;  // a copy: its own bytes
    b[2].n = 8;
    EXPECT_EQ(a[2].n, 7u);
    EXPECT_EQ(b[4].v[6], 1.5);
    EXPECT_EQ(reinterpret_cast<uintptr_t>(b.data()) % 64, 0u);
    ZeroedArray<Line> c = std::move(b);
    EXPECT_TRUE(b.empty());
    EXPECT_EQ(c[2].n, 8u);
    c = a;  // copy-assign over an array that had bytes of its own
    EXPECT_EQ(c[2].n, 7u);
    a = ZeroedArray<Line>(2);
    EXPECT_EQ(a.size(), 2u);
    EXPECT_EQ(a[1].n, 0u);
    EXPECT_EQ(c.size(), 5u);
}

size_t resident_bytes() {
    std::ifstream statm("/proc/self/statm");
    size_t pages = 0, resident = 0;
    statm >> pages >> resident;
    return resident * size_t(sysconf(_SC_PAGESIZE));
}

TEST(ZeroedArray, LargeFilmTouchesNoPixelUntilUsed) {
    // 2048 x 2048 accumulators of a cache line each: 256 MB. Value-initialised, all of it became
    // resident before the first sample (170 ms for 64 MB on a 2-core VM: the daemon's first tile
    // of a 1024 x 1024 job waited for it).
    FilmDesc d;
    d.width = 2048;
    d.height = 2048;
    const size_t before = resident_bytes();
    Film film(d);
    const size_t grown = resident_bytes() - before;
    EXPECT_LT(grown, size_t(64) << 20) << "constructing the film made " << (grown >> 20) << " MB resident";
    film.add_sample(2047, 2047, Rgb(1.f, 2.f, 3.f));
    EXPECT_EQ(film.pixel(2047, 2047).n, 1u);
    EXPECT_EQ(film.pixel(2047, 2047).mean[1], 2.0);
    EXPECT_EQ(film.pixel(0, 0).n, 0u);
    EXPECT_EQ(film.pixel(1024, 1024).mean[0], 0.0);
}

}  // namespace
}  // namespace omega
