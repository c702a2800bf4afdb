#include <gtest/gtest.h>

#include <cmath>

#include "bsdf/fresnel.h"
#include "bsdf/metals.h"
#include "bsdf/microfacet.h"
#include "chi2.h"
#include "test_util.h"

namespace omega {
namespace {

TEST(Fresnel, DielectricKnownValues) {
    EXPECT_NEAR(fresnel_dielectric(1.f, 1.5f).r, 0.04f, 1e-6f);
    EXPECT_NEAR(fresnel_dielectric(-1.f, 1.5f).r, 0.04f, 1e-6f);
    EXPECT_NEAR(fresnel_dielectric(0.f, 1.5f).r, 1.f, 1e-6f);
    // Total internal reflection beyond the critical angle (sin = 1/1.5) from inside.
    EXPECT_EQ(fresnel_dielectric(-0.7f, 1.5f).r, 1.f);
    EXPECT_LT(fresnel_dielectric(-0.76f, 1.5f).r, 1.f);
    // Same interface seen from both sides: F(theta_o, eta) = F(theta_t, 1/eta).
    DielectricFresnel a = fresnel_dielectric(0.3f, 1.5f);
    EXPECT_LT(a.cos_t, 0.f);
    EXPECT_NEAR(fresnel_dielectric(a.cos_t, 1.5f).r, a.r, 1e-5f);
    EXPECT_EQ(fresnel_dielectric(0.3f, 1.f).r, 0.f);
}

TEST(Fresnel, ConductorLimits) {
    // k = 0 reduces to the dielectric formula.
    for (float c : {1.f, 0.6f, 0.2f, 0.01f})
        EXPECT_NEAR(fresnel_conductor(c, 1.5f, 0.f), fresnel_dielectric(c, 1.5f).r, 1e-5f);
    EXPECT_NEAR(fresnel_conductor(1.f, 0.2f, 3.9f), (sqr(0.2f - 1) + sqr(3.9f)) / (sqr(0.2f + 1) + sqr(3.9f)), 1e-5f);
    EXPECT_NEAR(fresnel_conductor(0.f, 0.2f, 3.9f), 1.f, 1e-6f);
    EXPECT_TRUE(std::isfinite(fresnel_conductor(0.5f, 0.f, 0.f)));
}

TEST(Metals, NamedValues) {
    auto au = named_metal_ior("Au");
    ASSERT_TRUE(au);
    EXPECT_NEAR(au->first.x, 0.1431189557f, 1e-7f);
    EXPECT_NEAR(au->second.z, 1.6032152899f, 1e-7f);
    for (const char* n : {"Ag", "Cu", "Al"}) EXPECT_TRUE(named_metal_ior(n)) << n;
    EXPECT_FALSE(named_metal_ior("Unobtainium"));
    // Gold reflects red more than blue at normal incidence.
    Rgb f = fresnel_conductor(1.f, au->first, au->second);
    EXPECT_GT(f.x, f.z);
}

TEST(Microfacet, ErfinvInvertsErf) {
    for (double y : {-0.999999, -0.9, -0.3, 0.0, 0.2, 0.77, 0.9999999})
        EXPECT_NEAR(std::erf(erfinv(y)), y, 1e-13);
}

TEST(Microfacet, ProjectedAreaNormalisation) {
    // ∫ D(m) m.z dm = 1 and ∫ D(m) max(0, wo.m) G1(wo, m) dm = wo.z (visible projected area).
    Rng rng(71, 0);
    for (MicrofacetType t : {MicrofacetType::GGX, MicrofacetType::Beckmann})
        for (auto [au, av] : {std::pair{0.3f, 0.3f}, std::pair{0.2f, 0.6f}, std::pair{1.f, 1.f}}) {
            Microfacet md(t, au, av);
            Vec3 wo = bsdf_test::dir(0.4f, 0.5f);
            const int n = 400000;
            double sum_d = 0, sum_v = 0;
            for (int i = 0; i < n; ++i) {
                Vec3 m = bsdf_test::dir(rng.next_1d(), 2 * kPi * rng.next_1d());  // uniform hemisphere
                sum_d += double(md.D(m)) * m.z * 2 * kPiD;
                sum_v += double(md.pdf_visible_sa(wo, m)) * 2 * kPiD;
            }
            EXPECT_NEAR(sum_d / n, 1.0, 0.02) << int(t) << " " << au << " " << av;
            EXPECT_NEAR(sum_v / n, 1.0, 0.02) << int(t) << " " << au << " " << av;
        }
}

TEST(Microfacet, VisibleNormalSamplingChi2) {
    struct Case {
        MicrofacetType t;
        float au, av, cos_o;
    };
    const Case cases[] = {{MicrofacetType::GGX, 0.3f, 0.3f, 0.6f},       {MicrofacetType::GGX, 0.2f, 0.7f, 0.05f},
                          {MicrofacetType::Beckmann, 0.3f, 0.3f, 0.6f},  {MicrofacetType::Beckmann, 0.2f, 0.7f, 0.05f},
                          {MicrofacetType::Beckmann, 0.5f, 0.5f, 1.0f},  {MicrofacetType::Beckmann, 1.f, 1.f, 0.01f}};
    for (const Case& c : cases) {
        Microfacet md(c.t, c.au, c.av);
        Vec3 wo = bsdf_test::dir(c.cos_o, 0.8f);
        test::Chi2Options opt;
        opt.sample_count = 300'000;
        opt.test_count = int(std::size(cases));
        auto sampler = [&](Rng& rng) -> std::optional<test::DirSample> {
            Vec3 m = md.sample_visible(wo, bsdf_test::next_2d(rng));
            return test::DirSample{m, md.pdf_visible_sa(wo, m)};
        };
        test::Chi2Result r = test::chi2_sphere(
            sampler, [&](const Vec3& m) { return double(md.pdf_visible_sa(wo, m)); }, opt, 32, 64);
        std::string name = std::string("VNDF ") + (c.t == MicrofacetType::GGX ? "GGX" : "Beckmann") + " au=" +
                           std::to_string(c.au) + " av=" + std::to_string(c.av) + " cos=" + std::to_string(c.cos_o);
        test::print_result(name, r);
        EXPECT_TRUE(r.passed) << name << ": " << r.message;
        EXPECT_NEAR(r.pdf_integral, 1.0, 2e-3) << name;
    }
}

}  // namespace
}  // namespace omega
