#include "sampling/warp.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include "chi2.h"

namespace omega {
namespace {

using test::Chi2Options;
using test::Chi2Result;
using test::DirSample;
using test::PointSample;

// Family size for the Sidak correction across this file's chi-square tests.
constexpr int kTestCount = 10;

Chi2Options options() {
    Chi2Options o;
    o.sample_count = 1'000'000;
    o.test_count = kTestCount;
    return o;
}

Vec2 next_2d(Rng& rng) {
    float a = rng.next_1d();
    return {a, rng.next_1d()};
}

TEST(Chi2Harness, GammaQMatchesClosedForms) {
    // Q(1, x) = exp(-x); Q(1/2, x) = erfc(sqrt x).
    for (double x : {0.1, 1.0, 3.0, 20.0}) {
        EXPECT_NEAR(test::gamma_q(1.0, x), std::exp(-x), 1e-12);
        EXPECT_NEAR(test::gamma_q(0.5, x), std::erfc(std::sqrt(x)), 1e-12);
    }
    // Large dof: the chi-square median is about dof (1 - 2/(9 dof))^3.
    double dof = 4000;
    EXPECT_NEAR(test::chi2_p_value(dof * std::pow(1 - 2 / (9 * dof), 3), int(dof)), 0.5, 1e-3);
    EXPECT_NEAR(test::sidak_threshold(0.01, 1), 0.01, 1e-12);
}

TEST(Chi2Harness, RejectsPdfScaledBy1_1) {
    // The sampler is right, the pdf claims 10% more mass: the harness must notice.
    auto sampler = [](Rng& rng) -> std::optional<DirSample> {
        Vec3 w = square_to_cosine_hemisphere(next_2d(rng));
        return DirSample{w, 1.1 * cosine_hemisphere_pdf_sa(w)};
    };
    auto pdf = [](const Vec3& w) { return 1.1 * double(cosine_hemisphere_pdf_sa(w)); };
    Chi2Result r = test::chi2_sphere(sampler, pdf, options());
    test::print_result(::testing::UnitTest::GetInstance()->current_test_info()->name(), r);
    EXPECT_FALSE(r.passed) << r.message;
    EXPECT_NEAR(r.pdf_integral, 1.1, 1e-3);
}

TEST(Chi2Harness, RejectsSubtlyWrongShape) {
    // Sampling cos^1 but claiming cos^1.1 (renormalised): a small shape error, not a scale error.
    auto pdf = [](const Vec3& w) { return w.z > 0 ? std::pow(double(w.z), 1.1) * 2.1 / (2 * kPiD) : 0.0; };
    auto sampler = [&](Rng& rng) -> std::optional<DirSample> {
        Vec3 w = square_to_cosine_hemisphere(next_2d(rng));
        return DirSample{w, pdf(w)};
    };
    Chi2Result r = test::chi2_sphere(sampler, pdf, options());
    EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);
    test::print_result(::testing::UnitTest::GetInstance()->current_test_info()->name(), r);
    EXPECT_FALSE(r.passed) << r.message;
}

TEST(Warp, UniformDiskConcentric) {
    auto sampler = [](Rng& rng) -> std::optional<PointSample> {
        return PointSample{square_to_uniform_disk_concentric(next_2d(rng)), square_to_uniform_disk_pdf_area()};
    };
    // Supersampled Simpson of the disk indicator: integration error at the rim is tiny per cell.
    auto pdf = [](Vec2 p) { return p.x * p.x + p.y * p.y <= 1.f ? double(kInvPi) : 0.0; };
    Chi2Options o = options();
    o.subdivisions = 16;
    Chi2Result r = test::chi2_plane(sampler, pdf, {-1, -1, 1, 1}, o, 32, 32);
    // Rim cells cut by the circle are integrated only approximately, so the Cartesian test checks the
    // mass; the exact test runs in polar coordinates (r^2, phi), where the disk is a uniform square.
    EXPECT_NEAR(r.pdf_integral, 1.0, 2e-3);
    EXPECT_EQ(r.valid_samples, r.samples);
    auto polar = [](Rng& rng) -> std::optional<PointSample> {
        Vec2 d = square_to_uniform_disk_concentric(next_2d(rng));
        float r2 = d.x * d.x + d.y * d.y;
        float phi = std::atan2(d.y, d.x);
        if (phi < 0) phi += 2 * kPi;
        return PointSample{{r2, phi}, 1.0 / (2 * kPiD)};
    };
    Chi2Result rp = test::chi2_plane(polar, [](Vec2) { return 1.0 / (2 * kPiD); }, {0, 0, 1, 2 * kPiD}, options());
    test::print_result("UniformDiskConcentric (polar)", rp);
    EXPECT_TRUE(rp.passed) << rp.message;
}

TEST(Warp, SincosQuarterPiMatchesLibm) {
    // Every float in [-pi/4, pi/4] by a fine grid and the end points: against double precision.
    double worst_c = 0, worst_s = 0;
    const int n = 1 << 20;
    for (int i = 0; i <= n; ++i) {
        const float x = (kPi / 4.f) * (2.f * float(i) / float(n) - 1.f);
        const Vec2 cs = sincos_quarter_pi(x);
        worst_c = std::max(worst_c, std::abs(double(cs.x) - std::cos(double(x))));
        worst_s = std::max(worst_s, std::abs(double(cs.y) - std::sin(double(x))));
    }
    // An ulp of values in [0.7, 1] is 6e-8: within two of them.
    EXPECT_LT(worst_c, 1.2e-7);
    EXPECT_LT(worst_s, 1.2e-7);
    EXPECT_EQ(sincos_quarter_pi(0.f).x, 1.f);
    EXPECT_EQ(sincos_quarter_pi(0.f).y, 0.f);
}

// The concentric map picks its octant by selects (no branch): the branching form it replaced,
// bit for bit, so images did not move.
TEST(Warp, ConcentricDiskEqualsTheBranchingForm) {
    auto branching = [](Vec2 u) -> Vec2 {
        float ox = 2.f * u.x - 1.f, oy = 2.f * u.y - 1.f;
        if (ox == 0 && oy == 0) return {0, 0};
        if (std::abs(ox) > std::abs(oy)) {
            const Vec2 cs = sincos_quarter_pi((kPi / 4.f) * (oy / ox));
            return {ox * cs.x, ox * cs.y};
        }
        const Vec2 cs = sincos_quarter_pi((kPi / 4.f) * (ox / oy));
        return {oy * cs.y, oy * cs.x};
    };
    Rng rng(11, 0);
    std::vector<Vec2> us = {{0.5f, 0.5f}, {0.f, 0.f}, {0.25f, 0.25f}, {0.75f, 0.25f}, {0.5f, 0.f}, {1.f - 0x1p-24f, 0.5f}};
    for (int i = 0; i < 200000; ++i) us.push_back(next_2d(rng));
    for (Vec2 u : us) {
        const Vec2 a = square_to_uniform_disk_concentric(u), b = branching(u);
        EXPECT_EQ(std::bit_cast<uint32_t>(a.x), std::bit_cast<uint32_t>(b.x)) << u.x << " " << u.y;
        EXPECT_EQ(std::bit_cast<uint32_t>(a.y), std::bit_cast<uint32_t>(b.y)) << u.x << " " << u.y;
    }
}

// The cosine warp lifts the concentric disk point, unchanged, to the height its radius gives
// (sqrt(1 - r^2)): a unit vector to rounding, rim included, and the same x and y as the disk.
TEST(Warp, CosineHemisphereLiftsTheDiskPointToUnitLength) {
    Rng rng(12, 0);
    std::vector<Vec2> us = {{0.5f, 0.5f}, {0.f, 0.f}, {1.f - 0x1p-24f, 0.5f}, {0.5f, 1.f - 0x1p-24f},
                            {0.f, 0.5f}, {1.f - 0x1p-24f, 1.f - 0x1p-24f}, {0.5f + 0x1p-24f, 0.5f}};
    for (int i = 0; i < 200000; ++i) us.push_back(next_2d(rng));
    double worst = 0;
    for (Vec2 u : us) {
        const Vec3 w = square_to_cosine_hemisphere(u);
        const Vec2 d = square_to_uniform_disk_concentric(u);
        ASSERT_EQ(std::bit_cast<uint32_t>(w.x), std::bit_cast<uint32_t>(d.x)) << u.x << " " << u.y;
        ASSERT_EQ(std::bit_cast<uint32_t>(w.y), std::bit_cast<uint32_t>(d.y)) << u.x << " " << u.y;
        ASSERT_GT(w.z, 0.f) << u.x << " " << u.y;
        const double len = std::sqrt(double(w.x) * w.x + double(w.y) * w.y + double(w.z) * w.z);
        worst = std::max(worst, std::abs(len - 1.0));
    }
    EXPECT_LT(worst, 1e-6);
    EXPECT_EQ(square_to_cosine_hemisphere({0.5f, 0.5f}).z, 1.f);  // the centre: straight up
}

TEST(Warp, CosineHemisphere) {
    auto sampler = [](Rng& rng) -> std::optional<DirSample> {
        Vec3 w = square_to_cosine_hemisphere(next_2d(rng));
        return DirSample{w, cosine_hemisphere_pdf_sa(w)};
    };
    Chi2Result r = test::chi2_sphere(sampler, [](const Vec3& w) { return double(cosine_hemisphere_pdf_sa(w)); },
                                     options());
    test::print_result(::testing::UnitTest::GetInstance()->current_test_info()->name(), r);
    EXPECT_TRUE(r.passed) << r.message;
    EXPECT_NEAR(r.pdf_integral, 1.0, 1e-4);
}

TEST(Warp, UniformSphere) {
    auto sampler = [](Rng& rng) -> std::optional<DirSample> {
        return DirSample{square_to_uniform_sphere(next_2d(rng)), uniform_sphere_pdf_sa()};
    };
    Chi2Result r = test::chi2_sphere(sampler, [](const Vec3&) { return double(uniform_sphere_pdf_sa()); }, options());
    test::print_result(::testing::UnitTest::GetInstance()->current_test_info()->name(), r);
    EXPECT_TRUE(r.passed) << r.message;
    EXPECT_NEAR(r.pdf_integral, 1.0, 1e-4);
}

TEST(Warp, UniformHemisphere) {
    auto sampler = [](Rng& rng) -> std::optional<DirSample> {
        Vec3 w = square_to_uniform_hemisphere(next_2d(rng));
        return DirSample{w, uniform_hemisphere_pdf_sa(w)};
    };
    Chi2Result r = test::chi2_sphere(
        sampler, [](const Vec3& w) { return double(uniform_hemisphere_pdf_sa(w)); }, options());
    test::print_result(::testing::UnitTest::GetInstance()->current_test_info()->name(), r);
    EXPECT_TRUE(r.passed) << r.message;
    EXPECT_NEAR(r.pdf_integral, 1.0, 1e-4);
}

TEST(Warp, UniformCone) {
    // A cone edge falling inside a cos-theta cell would be integrated badly, so put it on a boundary.
    for (float cos_max : {0.5f, 0.9375f}) {
        auto sampler = [&](Rng& rng) -> std::optional<DirSample> {
            Vec3 w = square_to_uniform_cone(next_2d(rng), cos_max);
            return DirSample{w, uniform_cone_pdf_sa(w, cos_max)};
        };
        Chi2Result r = test::chi2_sphere(
            sampler, [&](const Vec3& w) { return double(uniform_cone_pdf_sa(w, cos_max)); }, options());
        EXPECT_TRUE(r.passed) << "cos_max " << cos_max << ": " << r.message;
        EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);
    }
}

TEST(Warp, UniformTriangle) {
    // (s^2, b1 / s) with s = b0 + b1 is uniform on the unit square exactly when (b0, b1) is uniform
    // on the triangle; testing there avoids integrating across the hypotenuse.
    auto sampler = [](Rng& rng) -> std::optional<PointSample> {
        Vec2 b = square_to_uniform_triangle(next_2d(rng));
        float s = b.x + b.y;
        if (!(b.x >= 0 && b.y >= 0 && s <= 1.f)) return PointSample{{-1, -1}, 1.0};  // counted invalid
        return PointSample{{s * s, s > 0 ? b.y / s : 0.f}, 1.0};
    };
    Chi2Result r = test::chi2_plane(sampler, [](Vec2) { return 1.0; }, {0, 0, 1, 1}, options());
    test::print_result(::testing::UnitTest::GetInstance()->current_test_info()->name(), r);
    EXPECT_TRUE(r.passed) << r.message;
    EXPECT_NEAR(r.pdf_integral, 1.0, 1e-6);
}

TEST(Warp, Tent) {
    auto sampler = [](Rng& rng) -> std::optional<PointSample> {
        float x = sample_tent(rng.next_1d()), y = sample_tent(rng.next_1d());
        return PointSample{{x, y}, double(tent_pdf(x)) * tent_pdf(y)};
    };
    auto pdf = [](Vec2 p) { return double(tent_pdf(p.x)) * tent_pdf(p.y); };
    Chi2Result r = test::chi2_plane(sampler, pdf, {-1, -1, 1, 1}, options());
    test::print_result(::testing::UnitTest::GetInstance()->current_test_info()->name(), r);
    EXPECT_TRUE(r.passed) << r.message;
    EXPECT_NEAR(r.pdf_integral, 1.0, 1e-4);
}

}  // namespace
}  // namespace omega
