// Texture lookups against hand-computed values, and image decoding against the sRGB closed form.
#include "io/file_gate.h"
#include "texture/bitmap_texture.h"

#include <gtest/gtest.h>

#include "scene/scene_error.h"
#include "scene/test_helpers.h"
#include "test_images.h"

using namespace omega;
using omega::test::scene_error_of;
using omega::test::TempDir;

namespace {

// A 2 x 2 image with one distinct grey per texel: (0,0) 0.1, (1,0) 0.2, (0,1) 0.3, (1,1) 0.4.
BitmapTexture grid2(TexFilter f, TexWrap w) {
    auto img = std::make_shared<Image>();
    img->width = img->height = 2;
    img->texels = {Rgb(0.1f), Rgb(0.2f), Rgb(0.3f), Rgb(0.4f)};
    BitmapTexture t;
    t.image = img;
    t.filter = f;
    t.wrap = w;
    return t;
}

float at(const BitmapTexture& t, float u, float v) { return t.eval({u, v}).x; }

TEST(BitmapTexture, NearestPicksTheTexelThatCoversUv) {
    auto t = grid2(TexFilter::Nearest, TexWrap::Repeat);
    EXPECT_FLOAT_EQ(at(t, 0.25f, 0.25f), 0.1f);
    EXPECT_FLOAT_EQ(at(t, 0.75f, 0.25f), 0.2f);  // u runs along a row
    EXPECT_FLOAT_EQ(at(t, 0.25f, 0.75f), 0.3f);  // v runs down the rows: v = 0 is the first row
    EXPECT_FLOAT_EQ(at(t, 0.99f, 0.99f), 0.4f);
    EXPECT_FLOAT_EQ(at(t, 0.49f, 0.51f), 0.3f);
}

TEST(BitmapTexture, BilinearInterpolatesBetweenTexelCentres) {
    auto t = grid2(TexFilter::Bilinear, TexWrap::Clamp);
    EXPECT_FLOAT_EQ(at(t, 0.25f, 0.25f), 0.1f);  // a texel centre is that texel
    EXPECT_FLOAT_EQ(at(t, 0.75f, 0.75f), 0.4f);
    EXPECT_NEAR(at(t, 0.5f, 0.5f), 0.25f, 1e-6f);          // the four centres' mean
    EXPECT_NEAR(at(t, 0.5f, 0.25f), 0.15f, 1e-6f);         // halfway along the first row
    EXPECT_NEAR(at(t, 0.375f, 0.625f), 0.1f * 0.75f * 0.25f + 0.2f * 0.25f * 0.25f + 0.3f * 0.75f * 0.75f +
                                           0.4f * 0.25f * 0.75f, 1e-6f);
    // Clamp: beyond the outer centres the edge texels hold.
    EXPECT_FLOAT_EQ(at(t, 0.f, 0.f), 0.1f);
    EXPECT_FLOAT_EQ(at(t, -3.f, 0.25f), 0.1f);
    EXPECT_FLOAT_EQ(at(t, 7.f, 7.f), 0.4f);
}

TEST(BitmapTexture, WrapModes) {
    auto rep = grid2(TexFilter::Nearest, TexWrap::Repeat);
    EXPECT_FLOAT_EQ(at(rep, 1.25f, 0.25f), 0.1f);
    EXPECT_FLOAT_EQ(at(rep, -0.25f, 0.25f), 0.2f);
    EXPECT_FLOAT_EQ(at(rep, 0.25f, -0.25f), 0.3f);
    EXPECT_FLOAT_EQ(at(rep, 10.75f, -9.25f), 0.4f);
    auto cl = grid2(TexFilter::Nearest, TexWrap::Clamp);
    EXPECT_FLOAT_EQ(at(cl, 1.25f, 0.25f), 0.2f);
    EXPECT_FLOAT_EQ(at(cl, -0.25f, 0.25f), 0.1f);
    auto mir = grid2(TexFilter::Nearest, TexWrap::Mirror);
    EXPECT_FLOAT_EQ(at(mir, 1.25f, 0.25f), 0.2f);   // the first repeat is mirrored
    EXPECT_FLOAT_EQ(at(mir, 1.75f, 0.25f), 0.1f);
    EXPECT_FLOAT_EQ(at(mir, 2.25f, 0.25f), 0.1f);   // the second is not
    EXPECT_FLOAT_EQ(at(mir, -0.25f, 0.25f), 0.1f);
    // Bilinear, repeat: at u = 0 the left neighbour of texel 0 is the last texel.
    auto brep = grid2(TexFilter::Bilinear, TexWrap::Repeat);
    EXPECT_NEAR(at(brep, 0.f, 0.25f), 0.15f, 1e-6f);
    EXPECT_EQ(wrap_index(-1, 5, TexWrap::Repeat), 4);
    EXPECT_EQ(wrap_index(-1, 5, TexWrap::Mirror), 0);
    EXPECT_EQ(wrap_index(5, 5, TexWrap::Mirror), 4);
    EXPECT_EQ(wrap_index(10, 5, TexWrap::Mirror), 0);
    EXPECT_EQ(wrap_index(-6, 5, TexWrap::Mirror), 4);
    EXPECT_EQ(wrap_index(1LL << 40, 5, TexWrap::Clamp), 4);
}

TEST(BitmapTexture, ToUvAppliesBeforeTheLookup) {
    auto t = grid2(TexFilter::Nearest, TexWrap::Repeat);
    t.to_uv.m = {2, 0, 0, 0, 1, 0.5f};  // u' = 2u, v' = v + 0.5
    EXPECT_FLOAT_EQ(at(t, 0.375f, 0.25f), 0.4f);  // (0.75, 0.75)
    UvTransform scale{{2, 0, 0, 0, 2, 0}}, shift{{1, 0, 0.5f, 0, 1, 0.25f}};
    Vec2 p = shift.after(scale).apply({1, 1});  // scale first, then shift
    EXPECT_FLOAT_EQ(p.x, 2.5f);
    EXPECT_FLOAT_EQ(p.y, 2.25f);
}

// Mitsuba 3's checkerboard: color0 where frac(u') > 1/2 equals frac(v') > 1/2, u' = to_uv(uv).
// With to_uv scale 4 (the thin-glass scene): 8 x 8 checks on [0, 1]^2, color0 at the corner.
TEST(BitmapTexture, CheckerboardAsMitsuba) {
    BitmapTexture t;
    t.checker = true;
    t.color0 = Rgb(0.8f);
    t.color1 = Rgb(0.1f, 0.1f, 0.15f);
    t.to_uv.m = {4, 0, 0, 0, 4, 0};
    EXPECT_EQ(t.eval({0.01f, 0.01f}), t.color0);  // frac 0.04, 0.04: both <= 1/2
    EXPECT_EQ(t.eval({0.2f, 0.01f}), t.color1);   // frac(0.8) > 1/2, frac(0.04) not
    EXPECT_EQ(t.eval({0.2f, 0.2f}), t.color0);
    EXPECT_EQ(t.eval({0.01f, 0.2f}), t.color1);
    EXPECT_EQ(t.eval({0.26f, 0.01f}), t.color0);  // the next check along u: 8 per unit
    EXPECT_EQ(t.eval({-0.01f, 0.01f}), t.color1); // repeats below 0 (frac of -0.04 is 0.96)
    EXPECT_EQ(t.eval({std::nanf(""), 0.01f}), t.color0);
    EXPECT_EQ(t.mean(), (t.color0 + t.color1) * 0.5f);
    // Default colours: Mitsuba's 0.4 / 0.2.
    BitmapTexture d;
    d.checker = true;
    EXPECT_EQ(d.eval({0.1f, 0.1f}), Rgb(0.4f));
    EXPECT_EQ(d.eval({0.6f, 0.1f}), Rgb(0.2f));
}

// The bump map's gradient: of the bilinear interpolant, in units of uv, through to_uv.
TEST(BitmapTexture, GradientOfTheBilinearInterpolant) {
    auto img = std::make_shared<Image>();
    img->width = 4;
    img->height = 2;
    // h = 0.25 i + 0.5 j at texel (i, j): slopes 0.25 x 4 = 1 per unit u, 0.5 x 2 = 1 per unit v.
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 4; ++i) img->texels.push_back(Rgb(0.25f * float(i) + 0.5f * float(j), 9.f, 9.f));
    BitmapTexture t;
    t.image = img;
    Vec2 g = t.eval_grad({0.5f, 0.5f});
    EXPECT_NEAR(g.x, 1.f, 1e-5f);
    EXPECT_NEAR(g.y, 1.f, 1e-5f);
    t.filter = TexFilter::Nearest;  // still the interpolant's gradient (see eval_grad)
    EXPECT_NEAR(t.eval_grad({0.5f, 0.5f}).x, 1.f, 1e-5f);
    t.to_uv.m = {2, 0, 0, 0, 3, 0};  // h(2u, 3v): the chain rule scales the slopes
    g = t.eval_grad({0.25f, 1.f / 6.f});
    EXPECT_NEAR(g.x, 2.f, 1e-5f);
    EXPECT_NEAR(g.y, 3.f, 1e-5f);
    BitmapTexture c;
    c.checker = true;
    EXPECT_EQ(c.eval_grad({0.3f, 0.3f}).x, 0.f);
    EXPECT_EQ(c.eval_grad({0.3f, 0.3f}).y, 0.f);
}

TEST(BitmapTexture, NonFiniteUvDoesNotReadOutOfRange) {
    auto t = grid2(TexFilter::Bilinear, TexWrap::Repeat);
    Rgb c = t.eval({std::nanf(""), INFINITY});
    EXPECT_TRUE(is_finite(c));
}

TEST(Image, EightBitIsSrgbDecodedUnlessRaw) {
    TempDir dir;
    std::vector<uint8_t> px = {0, 10, 128, 255, 200, 3, 64, 32, 16, 90, 180, 250};  // 2 x 2 RGB
    auto path = (dir.path / "t.png").string();
    test::write_image_u8(path, 2, 2, 3, px);
    auto img = load_image(*FileGate::unconfined(), path, false, "");
    ASSERT_EQ(img->width, 2);
    ASSERT_EQ(img->height, 2);
    for (size_t i = 0; i < 4; ++i)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(img->texels[i][c], test::srgb8_to_linear(px[3 * i + size_t(c)]), 2e-6) << i << " " << c;
    auto raw = load_image(*FileGate::unconfined(), path, true, "");
    for (size_t i = 0; i < 4; ++i)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(raw->texels[i][c], px[3 * i + size_t(c)] / 255.0, 1e-6);
    // Row 0 is the top row as written.
    EXPECT_NEAR(img->at(1, 0).x, test::srgb8_to_linear(255), 1e-6);
    EXPECT_NEAR(img->at(0, 1).x, test::srgb8_to_linear(64), 1e-6);
}

TEST(Image, GreyIsReplicatedAndAlphaIgnored) {
    TempDir dir;
    auto grey = (dir.path / "g.png").string(), rgba = (dir.path / "a.png").string();
    test::write_image_u8(grey, 1, 1, 1, {128});
    test::write_image_u8(rgba, 1, 1, 4, {255, 0, 128, 7});
    Rgb g = load_image(*FileGate::unconfined(), grey, false, "")->texels[0];
    EXPECT_EQ(g.x, g.y);
    EXPECT_EQ(g.x, g.z);
    EXPECT_NEAR(g.x, test::srgb8_to_linear(128), 2e-6);
    Rgb a = load_image(*FileGate::unconfined(), rgba, false, "")->texels[0];
    EXPECT_NEAR(a.z, test::srgb8_to_linear(128), 2e-6);
}

TEST(Image, FloatIsLinearAndClampedToOne) {
    TempDir dir;
    auto path = (dir.path / "t.exr").string();
    test::write_image_f32(path, 2, 1, 3, {0.3f, 0.02f, 0.7f, 5.f, 0.f, 1.f});
    auto img = load_image(*FileGate::unconfined(), path, false, "");
    EXPECT_FLOAT_EQ(img->texels[0].x, 0.3f);  // not decoded, even with raw = false
    EXPECT_FLOAT_EQ(img->texels[0].y, 0.02f);
    EXPECT_FLOAT_EQ(img->texels[1].x, 1.f);   // a reflectance cannot exceed 1
}

TEST(Image, BadFilesAreSceneErrorsNamingTheFile) {
    TempDir dir;
    auto junk = dir.write("junk.png", "this is not a png").string();
    std::string e = scene_error_of([&] { load_image(*FileGate::unconfined(), junk, false, "s.yaml:3: materials.m.reflectance: "); });
    EXPECT_NE(e.find("s.yaml:3: materials.m.reflectance: cannot read texture '" + junk + "'"), std::string::npos) << e;
    std::string missing = (dir.path / "missing.png").string();
    e = scene_error_of([&] { load_image(*FileGate::unconfined(), missing, false, ""); });
    EXPECT_NE(e.find("cannot open '" + missing + "': No such file"), std::string::npos) << e;
    auto nan = (dir.path / "nan.exr").string();
    test::write_image_f32(nan, 1, 1, 3, {0.5f, std::nanf(""), 0.5f});
    e = scene_error_of([&] { load_image(*FileGate::unconfined(), nan, false, ""); });
    EXPECT_NE(e.find("must be finite"), std::string::npos) << e;
}

}  // namespace
