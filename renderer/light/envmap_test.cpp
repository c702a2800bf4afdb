// The envmap light (light/envmap.h): Mitsuba 3's lookup convention, chi-square tests of its
// direction sampling, sampled pdf == pdf(), and the same densities through the Light interfaces
// that next-event estimation (light_sample_li) and light subpaths (light_sample_le, light_pdf_le)
// use.
#include <gtest/gtest.h>

#include <cmath>

#include "chi2.h"
#include "light/light.h"
#include "light/light_emission.h"
#include "render_harness.h"
#include "sampling/rng.h"
#include "scene/scene.h"

namespace omega {
namespace {

// A W x H map: a smooth sky gradient, darker ground, a black band (zero radiance: its patches
// must never be sampled) and a bright "sun" texel.
std::vector<Rgb> test_map(int w, int h) {
    std::vector<Rgb> px(size_t(w) * size_t(h));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float t = float(y) / float(h - 1);
            Rgb c = t < 0.5f ? Rgb{0.3f + 0.5f * t, 0.5f + t, 1.f} : Rgb{0.3f, 0.2f, 0.1f} * (1.f + float(x % 3));
            if (x >= w / 2 && x < w / 2 + 3 && y >= h / 2) c = Rgb(0.f);
            px[size_t(y) * size_t(w) + size_t(x)] = c;
        }
    px[size_t(2) * size_t(w) + size_t(3)] = Rgb{200.f, 180.f, 150.f};
    return px;
}

// Mitsuba 3: u = atan2(x, -z) / 2pi, texel-centred columns; v = acos(y) / pi, rows at the corners.
TEST(EnvMap, FollowsMitsubasLookupConvention) {
    const int w = 8, h = 5;
    std::vector<Rgb> px(size_t(w * h), Rgb(0.f));
    px[size_t(1 * w + 2)] = Rgb{4.f, 2.f, 1.f};  // texel (2, 1)
    EnvMap m(w, h, px, 0.5f, Mat4{});
    // The texel's own direction: u = (2 + 1/2) / 8, v = 1 / 4.
    Vec3 d = EnvMap::uv_to_direction({2.5f / 8.f, 0.25f});
    Rgb c = m.eval(d);
    EXPECT_NEAR(c.x, 2.f, 1e-4f);
    EXPECT_NEAR(c.y, 1.f, 1e-4f);
    EXPECT_NEAR(c.z, 0.5f, 1e-4f);
    // Half a texel to the right and half a row down: a quarter of it (bilinear).
    EXPECT_NEAR(m.eval(EnvMap::uv_to_direction({3.f / 8.f, 0.375f})).x, 0.5f, 1e-3f);
    // +y is row 0, -y row h-1; -z is u = 0 (between the last and the first column).
    EXPECT_NEAR(length(EnvMap::uv_to_direction({0.f, 0.5f}) - Vec3{0, 0, -1}), 0.f, 1e-6f);
    EXPECT_NEAR(length(EnvMap::uv_to_direction({0.25f, 0.5f}) - Vec3{1, 0, 0}), 0.f, 1e-6f);
    Vec2 uv = EnvMap::direction_to_uv(normalize(Vec3{1, 1, 0}));
    EXPECT_NEAR(uv.x, 0.25f, 1e-6f);
    EXPECT_NEAR(uv.y, 0.25f, 1e-6f);
    // Wrapping: a map whose only bright column is the last lights u = 0 (half) from both sides.
    std::vector<Rgb> col(size_t(w * h), Rgb(0.f));
    for (int y = 0; y < h; ++y) col[size_t(y * w + w - 1)] = Rgb(1.f);
    EnvMap mc(w, h, col, 1.f, Mat4{});
    EXPECT_NEAR(mc.eval(Vec3{0, 0, -1}).x, 0.5f, 1e-5f);
    EXPECT_NEAR(mc.eval(normalize(Vec3{-0.01f, 0, -1})).x, 0.5f + 0.01f / (2 * kPi) * 8, 2e-3f);
}

TEST(EnvMap, ToWorldRotatesTheMap) {
    const int w = 16, h = 9;
    Mat4 rot = Mat4::rotate({0.3, 1, -0.2}, 70);
    EnvMap plain(w, h, test_map(w, h), 1.f, Mat4{});
    EnvMap turned(w, h, test_map(w, h), 1.f, rot * Mat4::scale({2, 2, 2}));  // a uniform scale changes nothing
    Rng rng(5, 0);
    for (int i = 0; i < 1000; ++i) {
        Vec3 d = normalize(Vec3{rng.next_1d() - 0.5f, rng.next_1d() - 0.5f, rng.next_1d() - 0.5f});
        Vec3 dw = Vec3(normalize(rot.vector(Vec3d(d))));
        Rgb a = plain.eval(d), b = turned.eval(dw);
        EXPECT_NEAR(a.x, b.x, 1e-3f * (1 + a.x));
        EXPECT_NEAR(plain.pdf_sa(d), turned.pdf_sa(dw), 1e-3f * (1 + plain.pdf_sa(d)));
    }
    EXPECT_THROW(EnvMap(w, h, test_map(w, h), 1.f, Mat4::scale({1, 2, 1})), std::invalid_argument);
}

// In the plane of the patches, (u - 1/2W, v): the density is piecewise constant on the W x (H-1)
// patches, and the 64 x 64 grid's edges fall on theirs, so the expected counts are exact.
TEST(EnvMapChi2, PatchPlane) {
    const int w = 16, h = 9;
    EnvMap m(w, h, test_map(w, h), 1.f, Mat4{});
    test::Chi2Options opt;
    opt.sample_count = 400'000;
    opt.test_count = 2;
    opt.seed = 11;
    auto to_plane = [&](const Vec3& d) {
        Vec2 uv = EnvMap::direction_to_uv(d);
        float us = uv.x - 0.5f / float(w);
        if (us < 0) us += 1.f;
        return Vec2{us, uv.y};
    };
    auto sampler = [&](Rng& rng) -> std::optional<test::PointSample> {
        auto s = m.sample({rng.next_1d(), rng.next_1d()});
        if (!s) return std::nullopt;
        double st = std::sqrt(double(s->d.x) * s->d.x + double(s->d.z) * s->d.z);
        return test::PointSample{to_plane(s->d), double(s->pdf_sa) * 2 * kPiD * kPiD * st};
    };
    auto pdf = [&](Vec2 p) { return double(m.pdf_patch_plane(p)); };
    auto r = test::chi2_plane(sampler, pdf, {0, 0, 1, 1}, opt, 64, 64);
    test::print_result("envmap patch plane", r);
    EXPECT_TRUE(r.passed) << r.message;
    EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);
    EXPECT_EQ(r.pdf_mismatches, 0u);
}

// On the sphere, through to_world and the NEE interface of a built scene: the directions
// light_sample_li returns follow environment_pdf_li_sa, which is the density it claims.
TEST(EnvMapChi2, RotatedMapThroughNextEventSampling) {
    const int w = 32, h = 17;
    // Smooth enough that the chi-square grid's Gauss-Legendre integration of the piecewise
    // constant density is exact to far below the noise: blur test_map's structure away.
    std::vector<Rgb> px(size_t(w * h));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            px[size_t(y * w + x)] = Rgb(1.f + 0.8f * std::sin(2 * kPi * float(x) / float(w)) * float(y) / float(h));
    auto map = std::make_shared<const EnvMap>(w, h, px, 2.f, Mat4::rotate({1, 0.5, 0}, 40));
    Light light = EnvMapLight{map};
    SceneDesc d = test::empty_scene(4, 4);
    auto scene = Scene::build(d);
    test::Chi2Options opt;
    opt.sample_count = 50'000;  // the grid integrates the density adaptively: its steps cost time
    opt.test_count = 2;
    opt.seed = 12;
    size_t mismatches = 0;
    auto sampler = [&](Rng& rng) -> std::optional<test::DirSample> {
        auto ls = light_sample_li(*scene, light, Vec3(0.f), {rng.next_1d(), rng.next_1d()});
        if (!ls) return std::nullopt;
        EXPECT_TRUE(ls->infinite);
        float p = environment_pdf_li_sa(light, ls->wi);
        if (std::abs(p - ls->pdf_sa) > 1e-4f * p) ++mismatches;
        Rgb le = environment_le(light, ls->wi);
        if (std::abs(le.x - ls->Li.x) > 1e-5f * le.x) ++mismatches;
        return test::DirSample{ls->wi, ls->pdf_sa};
    };
    auto pdf = [&](const Vec3& wv) { return double(environment_pdf_li_sa(light, wv)); };
    auto r = test::chi2_sphere(sampler, pdf, opt, 16, 32);
    test::print_result("envmap rotated, sphere", r);
    EXPECT_TRUE(r.passed) << r.message;
    EXPECT_NEAR(r.pdf_integral, 1.0, 2e-3);
    EXPECT_EQ(mismatches, 0u);
}

// The harness can fail: a density that moves 5% of the mass between the halves of the map is
// rejected.
TEST(EnvMapChi2, RejectsAWrongDensity) {
    const int w = 16, h = 9;
    EnvMap m(w, h, test_map(w, h), 1.f, Mat4{});
    test::Chi2Options opt;
    opt.sample_count = 200'000;
    opt.seed = 13;
    auto pdf = [&](Vec2 p) { return double(m.pdf_patch_plane(p)) * (p.x < 0.5f ? 1.05 : 0.95); };
    auto sampler = [&](Rng& rng) -> std::optional<test::PointSample> {
        auto s = m.sample({rng.next_1d(), rng.next_1d()});
        if (!s) return std::nullopt;
        Vec2 uv = EnvMap::direction_to_uv(s->d);
        float us = uv.x - 0.5f / float(w);
        if (us < 0) us += 1.f;
        return test::PointSample{{us, uv.y}, pdf({us, uv.y})};
    };
    EXPECT_FALSE(test::chi2_plane(sampler, pdf, {0, 0, 1, 1}, opt, 64, 64).passed);
}

// Light subpaths: the direction density light_sample_le reports is the one light_pdf_le and
// infinite_light_pdf_dir give for the same ray (what BDPT's MIS recomputes), the origin lies on
// the disk of the scene's bounding radius, and the emission is the map's radiance.
TEST(EnvMap, EmissionDensitiesAgree) {
    const int w = 16, h = 9;
    SceneDesc d = test::empty_scene(4, 4);
    d.materials["white"] = test::diffuse("white", Rgb(0.5f));
    ShapeDesc s;
    s.type = ShapeType::Sphere;
    s.center = {1, 2, 3};
    s.radius = 2;
    s.material = "white";
    d.shapes.push_back(s);
    auto scene = Scene::build(d);
    Light light = EnvMapLight{std::make_shared<const EnvMap>(w, h, test_map(w, h), 1.f, Mat4::rotate({0, 1, 0}, 30))};
    Rng rng(3, 0);
    const float r = scene->bounds().radius();
    const Vec3 c = scene->bounds().center();
    for (int i = 0; i < 2000; ++i) {
        auto e = light_sample_le(*scene, light, {rng.next_1d(), rng.next_1d()}, {rng.next_1d(), rng.next_1d()});
        ASSERT_TRUE(e.has_value());
        EXPECT_TRUE(e->infinite);
        double pp, pd;
        light_pdf_le(*scene, light, Vec3(0.f), e->ray.d, pp, pd);
        EXPECT_NEAR(pd, e->pdf_dir, 1e-4 * pd);
        EXPECT_NEAR(pp, e->pdf_pos, 1e-6 * pp);
        EXPECT_NEAR(infinite_light_pdf_dir(light, e->ray.d), e->pdf_dir, 1e-4 * pd);
        Rgb le = environment_le(light, -e->ray.d);
        EXPECT_NEAR(le.y, e->Le.y, 1e-5f * (1 + le.y));
        // The ray starts on the disk of radius r at distance r from the centre, facing it.
        Vec3 o = e->ray.o - c;
        EXPECT_NEAR(dot(o, e->ray.d), -r, 1e-3f * r);
        EXPECT_LE(length(o - e->ray.d * dot(o, e->ray.d)), r * (1 + 1e-4f));
    }
    // Power for light selection: pi r^2 times the integral of the radiance over the sphere.
    EnvMap white(4, 3, std::vector<Rgb>(12, Rgb(1.f)), 1.f, Mat4{});
    EXPECT_NEAR(white.integral(), 4 * kPiD, 1e-9);
}

}  // namespace
}  // namespace omega
