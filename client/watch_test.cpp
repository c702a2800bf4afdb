// watch: tiles stream in (with a stale one out of order), the output EXR is the daemon's
// fetch image byte for byte.
#include <gtest/gtest.h>

#include <fstream>

#include "film/film.h"
#include "job_commands.h"
#include "test_fake_daemon.h"
#include "tile_canvas.h"

namespace omega::client {
namespace {

namespace proto = omega::protocol;
using test::FakeDaemon;
using test::TempDir;
namespace fs = std::filesystem;

std::string bytes(const std::vector<uint8_t>& v) { return std::string(v.begin(), v.end()); }

struct Render {
    Film film;
    std::vector<omega::Rect> tiles;
    Render() : film([] {
        FilmDesc d;
        d.width = 11;
        d.height = 7;
        d.crop = {1, 1, 10, 6};  // a crop: the data window is not the display window
        d.has_crop = true;
        return d;
    }()) {
        tiles = film.tiles(4);
    }
    void pass(int k) {
        for (int y = 1; y < 6; ++y)
            for (int x = 1; x < 10; ++x)
                for (int s = 0; s < 2; ++s)
                    film.add_sample(x, y, Rgb{float(x + k + s), float(y * k) + 0.25f * float(s), float(x * y + s)});
    }
};

ExrMeta meta(long long spp) {
    ExrMeta m;
    m.spp = spp;
    m.time_s = 0.5 * double(spp);
    m.integrator = "path";
    m.seed = 9;
    m.rel_error = 0.125;
    m.warnings = {"scene.yaml:1: a warning"};
    return m;
}

proto::Tile tile(const Render& r, size_t i, uint64_t pass, uint64_t version, const ExrMeta& m) {
    const omega::Rect& t = r.tiles[i];
    proto::Tile out;
    out.job = 42;
    out.rect = {uint32_t(t.x0), uint32_t(t.y0), uint32_t(t.x1), uint32_t(t.y1)};
    out.pass = pass;
    out.spp = uint64_t(m.spp);
    out.version = version;
    out.exr = bytes(encode_exr_tile(r.film, t, m));
    return out;
}

TEST(TileCanvas, NewestVersionWinsAndImageMatchesTheWholeFilm) {
    Render r;
    r.pass(1);
    std::vector<proto::Tile> old;
    for (size_t i = 0; i < r.tiles.size(); ++i) old.push_back(tile(r, i, 1, 1, meta(2)));
    r.pass(2);
    TileCanvas c;
    for (size_t i = 0; i < r.tiles.size(); ++i) EXPECT_TRUE(c.apply(tile(r, i, 2, 2, meta(4))));
    for (const auto& t : old) EXPECT_FALSE(c.apply(t));  // stale: dropped
    EXPECT_EQ(c.tiles(), r.tiles.size());
    EXPECT_EQ(bytes(c.encode()), bytes(encode_exr_tile(r.film, r.film.crop(), meta(4))));
    const ExrImage img = c.image();
    EXPECT_EQ(img.x0, 1);
    EXPECT_EQ(img.y0, 1);
    EXPECT_EQ(img.width, 9);
    EXPECT_EQ(img.display_width, 11);
}

TEST(TileCanvas, RefusesGarbageAndMismatchedRects) {
    Render r;
    r.pass(1);
    TileCanvas c;
    proto::Tile t = tile(r, 0, 1, 1, meta(2));
    proto::Tile junk = t;
    junk.exr = "not an exr";
    EXPECT_THROW(c.apply(junk), ClientError);
    proto::Tile moved = t;
    moved.rect.x1 += 1;
    EXPECT_THROW(c.apply(moved), ClientError);
    EXPECT_TRUE(c.empty());
}

// Resident memory in bytes (Linux).
long long resident_bytes() {
    std::ifstream f("/proc/self/statm");
    long long pages = 0, resident = 0;
    f >> pages >> resident;
    return resident * 4096;
}

// A tile from the network that claims the largest film the daemon allows (16384^2): the canvas
// allocates only the rows the tile covers, not 6 GiB for the whole film (found by fuzz_tile_exr;
// the input is in fuzz/regressions/tile_exr).
TEST(TileCanvas, HugeFilmCostsOnlyTheTilesRows) {
    ExrImage img;
    img.display_width = img.display_height = 16384;
    img.x0 = 100;
    img.y0 = 200;
    img.width = img.height = 2;
    img.rgb = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
    img.var.assign(12, 0.5f);
    const auto exr = encode_exr_image(img, ExrMeta{});
    proto::Tile t;
    t.id = t.job = t.pass = t.spp = t.version = 1;
    t.rect = {100, 200, 102, 202};
    t.exr.assign(exr.begin(), exr.end());
    const long long before = resident_bytes();
    TileCanvas c;
    ASSERT_TRUE(c.apply(t));
    EXPECT_LT(resident_bytes() - before, 64LL << 20);
    const ExrImage out = c.image();
    EXPECT_EQ(out.width, 2);
    EXPECT_EQ(out.display_width, 16384);
    EXPECT_EQ(out.rgb, img.rgb);
}

TEST(Watch, AssemblesStreamedTilesIntoTheFetchImage) {
    Render r;
    r.pass(1);
    std::vector<proto::Tile> pass1;
    for (size_t i = 0; i < r.tiles.size(); ++i) pass1.push_back(tile(r, i, 1, 1, meta(2)));
    r.pass(2);
    std::vector<proto::Tile> pass2;
    for (size_t i = 0; i < r.tiles.size(); ++i) pass2.push_back(tile(r, i, 2, 2, meta(4)));
    const std::string fetch_image = bytes(encode_exr_tile(r.film, r.film.crop(), meta(4)));

    FakeDaemon fake([&](FakeDaemon::Session& s, const proto::DecodedFrame& f) {
        if (f.type == proto::MessageType::status) {
            proto::JobInfo i;
            i.job = 42;
            i.name = "bunny";
            i.state = proto::JobState::running;
            i.halt.spp = 4;
            s.reply(proto::JobInfoReply{f.id, i});
        } else if (f.type == proto::MessageType::subscribe) {
            s.reply(proto::Ok{f.id});
            proto::ProgressInfo p{1, 2, 1.0, std::nullopt, 100.0};
            for (auto t : pass1) {
                t.id = f.id;
                s.reply(t);
            }
            s.reply(proto::Progress{f.id, 42, proto::JobState::running, p});
            // Pass 2, with tile 0's pass-1 version arriving late (it must not win).
            for (size_t i = 0; i < pass2.size(); ++i) {
                auto t = pass2[i];
                t.id = f.id;
                s.reply(t);
                if (i == 1) {
                    auto stale = pass1[0];
                    stale.id = f.id;
                    s.reply(stale);
                }
            }
            p = {2, 4, 2.0, 0.125, 100.0};
            s.reply(proto::Progress{f.id, 42, proto::JobState::running, p});
            s.reply(proto::Done{f.id, 42, proto::JobState::done, p, std::nullopt});
        } else if (f.type == proto::MessageType::fetch) {
            s.reply(proto::Image{f.id, 42, 2, 4, 11, 7, fetch_image});
        }
    });
    TempDir d;
    JobArgs a;
    a.host = fake.address();
    a.job = 42;
    a.output = (d.path / "watched.exr").string();
    a.write_interval_s = 0;  // rewrite after every tile
    testing::internal::CaptureStdout();
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_watch(a), kExitOk);
    const std::string out = testing::internal::GetCapturedStdout();
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(out.find("watched.exr: 4 spp"), std::string::npos) << out << err;
    EXPECT_NE(err.find("4/4 spp"), std::string::npos) << err;  // progress lines (not a terminal)
    EXPECT_EQ(test::slurp(a.output), fetch_image);
    EXPECT_FALSE(fs::exists(a.output + ".tmp"));

    // And `fetch` of the same job writes the very same file.
    JobArgs fa = a;
    fa.output = (d.path / "fetched.exr").string();
    testing::internal::CaptureStdout();
    EXPECT_EQ(run_fetch(fa), kExitOk);
    testing::internal::GetCapturedStdout();
    EXPECT_EQ(test::slurp(fa.output), test::slurp(a.output));
}

TEST(Watch, FailedJobExits1WithTheReason) {
    FakeDaemon fake([&](FakeDaemon::Session& s, const proto::DecodedFrame& f) {
        if (f.type == proto::MessageType::status) {
            proto::JobInfo i;
            i.job = 5;
            i.state = proto::JobState::queued;
            s.reply(proto::JobInfoReply{f.id, i});
        } else if (f.type == proto::MessageType::subscribe) {
            s.reply(proto::Ok{f.id});
            s.reply(proto::Done{f.id, 5, proto::JobState::failed, {}, std::string("out of memory")});
        }
    });
    TempDir d;
    JobArgs a;
    a.host = fake.address();
    a.job = 5;
    a.output = (d.path / "x.exr").string();
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_watch(a), kExitInternal);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("job 5 failed: out of memory"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(a.output));
}

}  // namespace
}  // namespace omega::client
