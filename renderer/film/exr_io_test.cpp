#include <gtest/gtest.h>

#include <ImfChannelList.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <unistd.h>

#include "film/film.h"
#include "film/test_util.h"
#include "shared_data.h"
#include "sampling/rng.h"

namespace omega {
namespace {

namespace fs = std::filesystem;

class TempDir {
public:
    TempDir() {
        path_ = fs::temp_directory_path() / ("omega_exr_test_" + std::to_string(::getpid()) + "_" +
                                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(path_);
        fs::create_directories(path_);
    }
    ~TempDir() { fs::remove_all(path_); }
    std::string file(const std::string& name) const { return (path_ / name).string(); }
    const fs::path& path() const { return path_; }

private:
    fs::path path_;
};

using test::cropped;

Film make_film() {
    Film f(cropped(13, 9, 2, 3, 11, 8));
    const Rect c = f.crop();
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            Rng rng = Rng::for_sample(77, uint64_t(y * 13 + x), 0);
            const int n = (x + y) % 4 == 0 ? 1 : 5;  // some pixels without a variance
            for (int i = 0; i < n; ++i)
                f.add_sample(x, y, Rgb(rng.next_1d() * float(x), 0.25f * float(y), rng.next_1d() * 1e3f));
        }
    return f;
}

ExrMeta make_meta() {
    ExrMeta m;
    m.spp = 1234;
    m.time_s = 12.345678901234567;
    m.integrator = "bdpt";
    m.seed = 18446744073709551557ULL;  // above 2^63: must survive as text
    m.nonfinite = 9007199254740993ULL;  // 2^53 + 1: would not survive a double
    m.warnings = {"light path class LS*E cannot be sampled", "second warning"};
    m.rel_error = 0.0123456789;
    return m;
}

void expect_matches(const ExrImage& img, const Film& f, const Rect& r) {
    ASSERT_EQ(img.width, r.width());
    ASSERT_EQ(img.height, r.height());
    EXPECT_EQ(img.x0, r.x0);
    EXPECT_EQ(img.y0, r.y0);
    EXPECT_EQ(img.display_width, f.width());
    EXPECT_EQ(img.display_height, f.height());
    ASSERT_EQ(img.rgb.size(), size_t(3 * r.area()));
    ASSERT_EQ(img.var.size(), size_t(3 * r.area()));
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
            const PixelStats s = f.pixel(x, y);
            const size_t i = size_t((y - r.y0) * r.width() + (x - r.x0));
            for (int c = 0; c < 3; ++c) {
                EXPECT_EQ(img.rgb[3 * i + size_t(c)], float(s.mean[c])) << x << "," << y;
                EXPECT_EQ(img.var[3 * i + size_t(c)], float(s.var_of_mean[c])) << x << "," << y;
            }
        }
}

void expect_meta(const ExrImage& img) {
    const auto& a = img.attributes;
    ASSERT_TRUE(a.count("omega.spp"));
    EXPECT_EQ(a.at("omega.spp"), "1234");
    EXPECT_EQ(std::stod(a.at("omega.time_s")), 12.345678901234567);
    EXPECT_EQ(a.at("omega.integrator"), "bdpt");
    EXPECT_EQ(a.at("omega.seed"), "18446744073709551557");
    EXPECT_EQ(a.at("omega.nonfinite"), "9007199254740993");
    EXPECT_EQ(a.at("omega.warnings"), "light path class LS*E cannot be sampled\nsecond warning");
    EXPECT_EQ(std::stod(a.at("omega.rel_error")), 0.0123456789);
    EXPECT_EQ(a.at("pixelAspectRatio"), "1");  // standard attributes come along too
}

TEST(Exr, WriteReadRoundTrip) {
    TempDir dir;
    const Film f = make_film();
    const std::string path = dir.file("out.exr");
    write_exr(path, f, make_meta());
    const ExrImage img = read_exr(path);
    expect_matches(img, f, f.crop());
    expect_meta(img);

    // Format details DESIGN.md fixes: float channels, ZIP, data window = crop.
    Imf::InputFile in(path.c_str());
    EXPECT_EQ(in.header().compression(), Imf::ZIP_COMPRESSION);
    int channels = 0;
    for (auto it = in.header().channels().begin(); it != in.header().channels().end(); ++it, ++channels)
        EXPECT_EQ(it.channel().type, Imf::FLOAT) << it.name();
    EXPECT_EQ(channels, 6);
    EXPECT_EQ(in.header().dataWindow().min.x, 2);
    EXPECT_EQ(in.header().dataWindow().max.y, 7);
    EXPECT_EQ(in.header().displayWindow().max.x, 12);
}

TEST(Exr, EmptyWarningsAreAnEmptyString) {
    TempDir dir;
    Film f(cropped(4, 4, 0, 0, 4, 4));
    write_exr(dir.file("a.exr"), f, ExrMeta{});
    const ExrImage img = read_exr(dir.file("a.exr"));
    EXPECT_EQ(img.attributes.at("omega.warnings"), "");
    EXPECT_EQ(img.attributes.at("omega.seed"), "0");
}

TEST(Exr, AtomicWriteLeavesNoTempFileAndReplaces) {
    TempDir dir;
    const std::string path = dir.file("out.exr");
    Film f = make_film();
    write_exr(path, f, make_meta());
    f.clear();
    f.add_sample(5, 5, Rgb(7.f));
    write_exr(path, f, make_meta());  // overwrite in place
    EXPECT_FALSE(fs::exists(path + ".tmp"));
    int entries = 0;
    for ([[maybe_unused]] auto& e : fs::directory_iterator(dir.path())) ++entries;
    EXPECT_EQ(entries, 1);
    const ExrImage img = read_exr(path);
    const size_t i = size_t((5 - 3) * 9 + (5 - 2));
    EXPECT_EQ(img.rgb[3 * i], 7.f);
}

TEST(Exr, ErrorsNameThePath) {
    TempDir dir;
    const std::string bad = dir.file("no/such/dir/out.exr");
    try {
        write_exr(bad, make_film(), make_meta());
        FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
    const std::string missing = dir.file("missing.exr");
    try {
        read_exr(missing);
        FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
    }
    // Not an EXR at all.
    const std::string junk = dir.file("junk.exr");
    FILE* fp = std::fopen(junk.c_str(), "wb");
    std::fputs("this is not an image", fp);
    std::fclose(fp);
    EXPECT_THROW(read_exr(junk), std::runtime_error);
}

TEST(Exr, ReadsTungstenReference) {
    const std::string path = test::shared_path("scenes/cornell-box/TungstenRender.exr");
    if (!test::shared_available(path)) GTEST_SKIP() << path << " not present";
    const ExrImage img = read_exr(path);
    EXPECT_EQ(img.width, 1024);
    EXPECT_EQ(img.height, 1024);
    ASSERT_EQ(img.rgb.size(), size_t(3 * 1024 * 1024));
    EXPECT_TRUE(img.var.empty());
    double sum = 0;
    for (float v : img.rgb) {
        ASSERT_TRUE(std::isfinite(v));
        sum += v;
    }
    EXPECT_GT(sum, 0.0);  // not an all-black decode
}

TEST(Exr, TileEncodeDecodeRoundTrip) {
    const Film f = make_film();
    const Rect tile{4, 3, 8, 6};
    const auto bytes = encode_exr_tile(f, tile, make_meta());
    const ExrImage img = decode_exr_memory(bytes);
    expect_matches(img, f, tile);
    expect_meta(img);
    // Every tile of the crop round-trips, edge tiles included.
    for (const Rect& t : f.tiles(4)) expect_matches(decode_exr_memory(encode_exr_tile(f, t, ExrMeta{})), f, t);
    EXPECT_THROW(encode_exr_tile(f, Rect{0, 0, 4, 4}, ExrMeta{}), std::invalid_argument);
    EXPECT_THROW(decode_exr_memory(bytes, 5), std::runtime_error);  // over the pixel limit
    // Uncompressed (the daemon's streamed tiles): the same pixels, and NONE in the header. The
    // compression attribute is 1 byte after its name and type ("compression\0compression\0",
    // size 1): 0 is NONE, 3 ZIP.
    ExrMeta raw = make_meta();
    raw.compress = false;
    const auto plain = encode_exr_tile(f, tile, raw);
    expect_matches(decode_exr_memory(plain), f, tile);
    auto compression_of = [](const std::vector<uint8_t>& b) {
        const std::string key("compression\0compression\0\1\0\0\0", 28);
        const std::string s(b.begin(), b.end());
        const size_t at = s.find(key);
        return at == std::string::npos ? -1 : int(uint8_t(s[at + key.size()]));
    };
    EXPECT_EQ(compression_of(plain), 0);
    EXPECT_EQ(compression_of(bytes), 3);
}

TEST(Exr, DecodeRejectsTruncatedAndGarbageInput) {
    const Film f = make_film();
    const auto good = encode_exr_tile(f, Rect{2, 3, 11, 8}, make_meta());
    ASSERT_NO_THROW(decode_exr_memory(good));
    EXPECT_THROW(decode_exr_memory({}), std::runtime_error);
    for (size_t len = 0; len < good.size(); len += (len < 400 ? 1 : 13))
        EXPECT_THROW(decode_exr_memory(std::span(good.data(), len)), std::runtime_error) << "length " << len;
    Rng rng(1, 2);
    for (int trial = 0; trial < 200; ++trial) {
        std::vector<uint8_t> garbage(size_t(rng.next_u32() % 4096));
        for (auto& b : garbage) b = uint8_t(rng.next_u32());
        if (trial % 2 && garbage.size() >= 4) {
            // Valid magic and version so the parser goes further before it fails.
            garbage[0] = 0x76, garbage[1] = 0x2f, garbage[2] = 0x31, garbage[3] = 0x01;
        }
        EXPECT_THROW(decode_exr_memory(garbage), std::runtime_error) << "trial " << trial;
    }
    // Random byte corruption of a valid tile: may decode (pixel data) or throw, never crash.
    int rejected = 0;
    for (int trial = 0; trial < 300; ++trial) {
        auto bad = good;
        bad[rng.next_u32() % bad.size()] ^= uint8_t(1 + rng.next_u32() % 255);
        try {
            decode_exr_memory(bad);
        } catch (const std::runtime_error&) {
            ++rejected;
        }
    }
    EXPECT_GT(rejected, 0);
}

}  // namespace
}  // namespace omega
