// Reciprocity, energy conservation, sample/eval/pdf consistency, delta lobes and robustness.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "bsdf/bsdf.h"
#include "bsdf/fresnel.h"
#include "test_util.h"

namespace omega {
namespace {

using bsdf_test::close_rel;
using bsdf_test::dir;
using bsdf_test::next_2d;
using bsdf_test::random_sphere_dir;
constexpr TransportMode kRad = TransportMode::Radiance;
constexpr TransportMode kImp = TransportMode::Importance;

struct Named {
    const char* name;
    Bsdf bsdf;
};

ConductorBsdf conductor(MicrofacetType t, float au, float av, bool ior = true) {
    ConductorBsdf c;
    c.alpha_u = au;
    c.alpha_v = av;
    c.distribution = t;
    c.has_ior = ior;
    c.eta = {0.2f, 0.9f, 1.1f};
    c.k = {3.9f, 2.4f, 2.1f};
    return c;
}
DielectricBsdf dielectric(MicrofacetType t, float au, float av, float eta = 1.5f) {
    DielectricBsdf d;
    d.eta = eta;
    d.alpha_u = au;
    d.alpha_v = av;
    d.distribution = t;
    return d;
}

PlasticBsdf plastic(float alpha, MicrofacetType t = MicrofacetType::GGX, bool nonlinear = false, Rgb rho = {0.8f, 0.5f, 0.2f},
                    float eta = 1.5f) {
    PlasticBsdf p;
    p.set_eta(eta);
    p.alpha = alpha;
    p.distribution = t;
    p.nonlinear = nonlinear;
    p.diffuse_reflectance = rho;
    return p;
}

std::vector<Named> rough_models() {
    return {{"diffuse", DiffuseBsdf{{0.8f, 0.5f, 0.2f}, true}},
            {"diffuse_one_sided", DiffuseBsdf{{0.8f, 0.5f, 0.2f}, false}},
            {"roughdiffuse", DiffuseBsdf{{0.8f, 0.5f, 0.2f}, true, nullptr, 0.5f, false}},
            {"roughdiffuse_fast_one_sided", DiffuseBsdf{{0.8f, 0.5f, 0.2f}, false, nullptr, 0.3f, true}},
            {"roughdiffuse_extreme", DiffuseBsdf{{0.9f, 0.9f, 0.9f}, true, nullptr, 3.f, false}},
            {"conductor_ggx", conductor(MicrofacetType::GGX, 0.3f, 0.3f)},
            {"conductor_beckmann_aniso", conductor(MicrofacetType::Beckmann, 0.1f, 0.5f)},
            {"conductor_ggx_aniso", conductor(MicrofacetType::GGX, 0.6f, 0.15f)},
            {"dielectric_ggx", dielectric(MicrofacetType::GGX, 0.3f, 0.3f)},
            {"dielectric_beckmann_aniso", dielectric(MicrofacetType::Beckmann, 0.4f, 0.1f)},
            {"dielectric_ggx_eta_lt_1", dielectric(MicrofacetType::GGX, 0.2f, 0.2f, 1.f / 1.33f)},
            {"roughplastic_ggx", plastic(0.2f)},
            {"roughplastic_beckmann_nonlinear", plastic(0.5f, MicrofacetType::Beckmann, true)},
            {"roughplastic_ggx_sharp_ks", [] {
                 PlasticBsdf p = plastic(0.02f, MicrofacetType::GGX, false, {0.3f, 0.3f, 0.9f}, 1.9f);
                 p.specular_reflectance = {0.2f, 0.5f, 1.f};
                 return p;
             }()},
            {"roughplastic_one_sided", [] {
                 PlasticBsdf p = plastic(0.3f);
                 p.two_sided = false;
                 return p;
             }()}};
}

// IOR on wi's side over IOR on wo's side (1 for reflection).
float etap(const DielectricBsdf& d, const Vec3& wo, const Vec3& wi) {
    if (wo.z * wi.z > 0) return 1.f;
    return wo.z > 0 ? d.eta : 1.f / d.eta;
}

TEST(BsdfProperties, Reciprocity) {
    Rng rng(21, 0);
    for (const Named& m : rough_models()) {
        int checked = 0;
        for (int i = 0; i < 20000; ++i) {
            Vec3 wo = random_sphere_dir(rng), wi = random_sphere_dir(rng);
            if (std::abs(wo.z) < 1e-3f || std::abs(wi.z) < 1e-3f) continue;
            Rgb f = bsdf_eval(m.bsdf, wo, wi, kRad), g = bsdf_eval(m.bsdf, wi, wo, kRad);
            float scale = 1.f;
            if (auto* d = std::get_if<DielectricBsdf>(&m.bsdf)) {
                // Radiance BSDF across a refraction: f(wo, wi) etap^2 = f(wi, wo); and the
                // importance BSDF is the adjoint: f_imp(wo, wi) = f(wi, wo).
                scale = sqr(etap(*d, wo, wi));
                Rgb fi = bsdf_eval(m.bsdf, wo, wi, kImp);
                for (int c = 0; c < 3; ++c)
                    ASSERT_TRUE(close_rel(fi[c], g[c], 2e-3, 1e-5)) << m.name << " adjoint " << fi[c] << " " << g[c] << " wo.z=" << wo.z << " wi.z=" << wi.z << " dot=" << dot(wo, wi);
            }
            if (std::holds_alternative<PlasticBsdf>(m.bsdf)) {
                // No refraction of its own: the adjoint is the same function.
                ASSERT_EQ(bsdf_eval(m.bsdf, wo, wi, kImp), f) << m.name;
                ASSERT_EQ(bsdf_pdf_sa(m.bsdf, wo, wi, kImp), bsdf_pdf_sa(m.bsdf, wo, wi, kRad)) << m.name;
            }
            for (int c = 0; c < 3; ++c)
                ASSERT_TRUE(close_rel(f[c] * scale, g[c], 2e-3, 1e-5))
                    << m.name << " wo=(" << wo.x << "," << wo.y << "," << wo.z << ") wi=(" << wi.x << "," << wi.y
                    << "," << wi.z << ") " << f[c] * scale << " vs " << g[c];
            if (!is_black(f)) ++checked;
        }
        EXPECT_GT(checked, 1000) << m.name;
    }
}

TEST(BsdfProperties, SampleConsistentWithEvalAndPdf) {
    Rng rng(22, 0);
    for (const Named& m : rough_models())
        for (TransportMode mode : {kRad, kImp}) {
            int n_ok = 0;
            for (int i = 0; i < 20000; ++i) {
                Vec3 wo = random_sphere_dir(rng);
                float uc = rng.next_1d();
                auto s = bsdf_sample(m.bsdf, wo, uc, next_2d(rng), mode);
                if (!s) continue;
                ASSERT_FALSE(s->is_delta());
                ASSERT_TRUE(s->pdf_sa > 0 && std::isfinite(s->pdf_sa));
                float pdf_sa = bsdf_pdf_sa(m.bsdf, wo, s->wi, mode);
                ASSERT_TRUE(close_rel(pdf_sa, s->pdf_sa, 2e-3, 1e-5)) << m.name << " " << pdf_sa << " vs " << s->pdf_sa;
                Rgb expect = bsdf_eval(m.bsdf, wo, s->wi, mode) * (std::abs(s->wi.z) / s->pdf_sa);
                for (int c = 0; c < 3; ++c)
                    ASSERT_TRUE(close_rel(expect[c], s->weight[c], 2e-3, 1e-5))
                        << m.name << " weight " << s->weight[c] << " vs " << expect[c] << " wo.z=" << wo.z;
                ASSERT_TRUE(s->lobe & (kLobeReflection | kLobeTransmission));
                bool refl = s->wi.z * wo.z > 0;
                ASSERT_EQ(refl, bool(s->lobe & kLobeReflection)) << m.name;
                ++n_ok;
            }
            EXPECT_GT(n_ok, 5000) << m.name;
        }
}

// Mean and standard error of the sampled weight: the directional albedo.
struct Albedo {
    Rgb mean{0.f}, std_err{0.f};
};
Albedo albedo_by_sampling(const Bsdf& b, const Vec3& wo, TransportMode mode, int n, uint64_t seed) {
    Rng rng(seed, 0);
    Vec3d sum(0.0), sum2(0.0);
    for (int i = 0; i < n; ++i) {
        float uc = rng.next_1d();
        auto s = bsdf_sample(b, wo, uc, next_2d(rng), mode);
        if (!s) continue;
        Vec3d w(s->weight);
        sum += w;
        sum2 += w * w;
    }
    Albedo a;
    for (int c = 0; c < 3; ++c) {
        double mu = sum[c] / n, var = std::max(0.0, sum2[c] / n - mu * mu);
        a.mean[c] = float(mu);
        a.std_err[c] = float(std::sqrt(var / n));
    }
    return a;
}

TEST(BsdfProperties, WhiteFurnaceAlbedoAtMostOne) {
    // Importance mode gives the flux albedo, which must not exceed 1 (radiance mode scales
    // refraction by 1/etap^2 and may legitimately exceed 1 from inside a denser medium).
    std::vector<Named> models = {{"diffuse_white", DiffuseBsdf{{1, 1, 1}, true}},
                                 // Oren-Nayar's full model at rho = 1 reflects more than it receives at
                                 // grazing incidence (below); at rho = 0.9 it stays within 1.
                                 {"roughdiffuse_0p9", DiffuseBsdf{{0.9f, 0.9f, 0.9f}, true, nullptr, 0.5f, false}},
                                 {"roughdiffuse_0p9_extreme", DiffuseBsdf{{0.9f, 0.9f, 0.9f}, true, nullptr, 5.f, false}},
                                 {"roughdiffuse_white_fast", DiffuseBsdf{{1, 1, 1}, true, nullptr, 1.f, true}},
                                 {"conductor_ggx_F1", conductor(MicrofacetType::GGX, 0.5f, 0.5f, false)},
                                 {"conductor_beckmann_F1", conductor(MicrofacetType::Beckmann, 1.f, 0.3f, false)},
                                 {"dielectric_ggx", dielectric(MicrofacetType::GGX, 0.5f, 0.5f)},
                                 {"dielectric_beckmann", dielectric(MicrofacetType::Beckmann, 0.3f, 0.3f)},
                                 {"dielectric_ggx_rough", dielectric(MicrofacetType::GGX, 1.f, 1.f)}};
    for (const Named& m : models)
        for (float c : {1.f, 0.5f, 0.1f, 0.01f, -0.5f, -0.05f}) {
            Albedo a = albedo_by_sampling(m.bsdf, dir(c, 0.3f), kImp, 40000, 31);
            EXPECT_LE(a.mean.x, 1.f + 4.f * a.std_err.x + 1e-4f) << m.name << " cos " << c;
            EXPECT_TRUE(is_finite(a.mean));
        }
    // Oren-Nayar's qualitative model with its interreflection term (Mitsuba's roughdiffuse, kept as
    // Mitsuba has it so that scenes match) is not energy conserving at rho = 1: measured 1.022 at
    // cos 0.1 and 1.046 at cos 0.01 for alpha 0.5. Bounded here so that a change shows.
    for (float alpha : {0.2f, 0.5f, 1.f, 5.f})
        for (float c : {1.f, 0.5f, 0.1f, 0.01f}) {
            Albedo a = albedo_by_sampling(DiffuseBsdf{{1, 1, 1}, true, nullptr, alpha, false}, dir(c, 0.3f), kImp, 40000, 32);
            EXPECT_LE(a.mean.x, 1.06f) << "roughdiffuse alpha " << alpha << " cos " << c;
            EXPECT_GT(a.mean.x, 0.5f) << "roughdiffuse alpha " << alpha << " cos " << c;
        }
    // Lambert with R = 1 is exactly 1 per sample.
    Albedo d = albedo_by_sampling(DiffuseBsdf{{1, 1, 1}, true}, dir(0.3f, 0.f), kRad, 1000, 3);
    EXPECT_NEAR(d.mean.x, 1.f, 1e-6f);
    // Nearly smooth F = 1 conductor at normal incidence loses almost nothing to masking.
    Albedo g = albedo_by_sampling(conductor(MicrofacetType::GGX, 0.01f, 0.01f, false), dir(1.f, 0.f), kRad, 20000, 4);
    EXPECT_GT(g.mean.x, 0.99f);
    EXPECT_LE(g.mean.x, 1.f + 1e-5f);
}

TEST(BsdfProperties, AlbedoBySamplingMatchesAlbedoByQuadrature) {
    // Independent estimate: uniform sphere directions with eval * |cos| / (1 / 4 pi). Catches any
    // disagreement between eval and the sampling weights in aggregate.
    for (const Named& m : rough_models()) {
        for (float c : {0.7f, 0.2f, -0.6f}) {
            Vec3 wo = dir(c, 1.1f);
            Albedo s = albedo_by_sampling(m.bsdf, wo, kRad, 100000, 41);
            Rng rng(42, 0);
            const int n = 200000;
            double sum = 0, sum2 = 0;
            for (int i = 0; i < n; ++i) {
                Vec3 wi = random_sphere_dir(rng);
                double v = double(bsdf_eval(m.bsdf, wo, wi, kRad).y) * std::abs(wi.z) * 4 * kPiD;
                sum += v;
                sum2 += v * v;
            }
            double mu = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mu * mu) / n);
            double tol = 5 * std::sqrt(se * se + double(s.std_err.y) * s.std_err.y) + 1e-4;
            EXPECT_NEAR(s.mean.y, mu, tol) << m.name << " cos " << c;
        }
    }
}

TEST(BsdfProperties, SmoothConductorIsPerfectMirror) {
    ConductorBsdf mirror;  // no IOR: F = 1
    ConductorBsdf gold = conductor(MicrofacetType::GGX, 0, 0);
    gold.specular_reflectance = {0.9f, 0.8f, 0.7f};
    for (float c : {1.f, 0.5f, 0.01f, -0.3f}) {
        Vec3 wo = dir(c, 0.4f);
        auto s = bsdf_sample(mirror, wo, 0.5f, {0.3f, 0.7f}, kRad);
        ASSERT_TRUE(s);
        EXPECT_TRUE(s->is_delta());
        EXPECT_EQ(s->pdf_sa, 1.f);
        EXPECT_EQ(s->weight, Rgb(1.f));
        EXPECT_NEAR(s->wi.x, -wo.x, 1e-7f);
        EXPECT_NEAR(s->wi.y, -wo.y, 1e-7f);
        EXPECT_EQ(s->wi.z, wo.z);
        auto g = bsdf_sample(gold, wo, 0.5f, {0.3f, 0.7f}, kRad);
        ASSERT_TRUE(g);
        Rgb expect = fresnel_conductor(std::abs(c), gold.eta, gold.k) * gold.specular_reflectance;
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(g->weight[k], expect[k], 1e-6f);
        EXPECT_EQ(bsdf_eval(mirror, wo, s->wi, kRad), Rgb(0.f));
        EXPECT_EQ(bsdf_pdf_sa(mirror, wo, s->wi, kRad), 0.f);
    }
    EXPECT_TRUE(bsdf_is_delta_only(mirror));
}

TEST(BsdfProperties, SmoothDielectricDiscreteProbabilitiesAndWeights) {
    DielectricBsdf glass;  // eta 1.5, smooth
    for (float c : {1.f, 0.7f, 0.2f, 0.01f, -0.9f, -0.75f, -0.6f, -0.01f}) {
        Vec3 wo = dir(c, 0.9f);
        DielectricFresnel fr = fresnel_dielectric(c, glass.eta);
        const int n = 100000;
        Rng rng(51, 0);
        int n_refl = 0;
        for (int i = 0; i < n; ++i) {
            auto s = bsdf_sample(glass, wo, rng.next_1d(), next_2d(rng), kRad);
            ASSERT_TRUE(s);
            ASSERT_TRUE(s->is_delta());
            ASSERT_NEAR(length(s->wi), 1.f, 1e-5f);
            auto si = bsdf_sample(glass, wo, 0.f, {0, 0}, kImp);
            ASSERT_TRUE(si);
            if (s->lobe & kLobeReflection) {
                ++n_refl;
                ASSERT_NEAR(s->pdf_sa, fr.r, 1e-6f);
                ASSERT_EQ(s->weight, Rgb(1.f));
                ASSERT_EQ(s->wi.z, wo.z);
                ASSERT_EQ(s->eta, 1.f);
            } else {
                ASSERT_NEAR(s->pdf_sa, 1 - fr.r, 1e-6f);
                ASSERT_LT(s->wi.z * wo.z, 0.f);
                // Snell: eta_o sin_o = eta_i sin_i; radiance weight 1/etap^2 with etap = eta_i / eta_o.
                float eta_o = wo.z > 0 ? 1.f : glass.eta, eta_i = wo.z > 0 ? glass.eta : 1.f;
                ASSERT_NEAR(eta_o * std::sqrt(sin2_theta(wo)), eta_i * std::sqrt(sin2_theta(s->wi)), 1e-5f);
                ASSERT_NEAR(s->weight.x, sqr(eta_o / eta_i), 1e-5f);
                ASSERT_NEAR(s->eta, eta_i / eta_o, 1e-6f);
                // Importance transport carries no radiance scaling.
                auto s_imp = bsdf_sample(glass, wo, 0.999999f, {0, 0}, kImp);
                ASSERT_TRUE(s_imp);
                ASSERT_EQ(s_imp->weight, Rgb(1.f));
            }
        }
        // Binomial check of P(reflect) = F within 5 standard deviations.
        double sd = std::sqrt(n * fr.r * (1 - fr.r)) + 0.5;
        EXPECT_NEAR(n_refl, n * fr.r, 5 * sd) << "cos " << c;
        bool tir = c < 0 && glass.eta * glass.eta * (1 - c * c) >= 1;
        if (tir) {
            EXPECT_EQ(n_refl, n) << "total internal reflection at cos " << c;
        }
    }
    EXPECT_TRUE(bsdf_is_delta_only(glass));
}

// Thin sheet (thin_dielectric.cpp): both lobes delta, chosen with the discrete probabilities R'
// and 1 - R', weights Ks and Kt, the same from both sides and in both transport modes.
TEST(ThinDielectricBsdf, DiscreteProbabilitiesWeightsAndSymmetry) {
    ThinDielectricBsdf pane{1.5f, {0.9f, 0.8f, 0.7f}, {0.6f, 0.5f, 0.4f}};
    // Tungsten's thinFilmReflectance (per-polarisation sum), by hand: at normal incidence
    // r = 0.04, R' = 2r/(1 + r) = 0.0769231; at 45 deg 0.0927, at 60 deg 0.1519
    // (../shared/scenes/materials/README.md).
    EXPECT_NEAR(thin_slab_reflectance(1.f, 1.5f), 0.08f / 1.04f, 1e-6f);
    EXPECT_NEAR(thin_slab_reflectance(std::sqrt(0.5f), 1.5f), 0.0927f, 1e-4f);
    EXPECT_NEAR(thin_slab_reflectance(0.5f, 1.5f), 0.1519f, 1e-4f);
    EXPECT_EQ(thin_slab_reflectance(0.3f, 1.f), 0.f);
    EXPECT_EQ(thin_slab_reflectance(0.1f, 0.7f), 1.f);  // eta < 1: total internal reflection
    EXPECT_NEAR(thin_slab_reflectance(1e-6f, 1.5f), 1.f, 1e-4f);  // grazing: a mirror
    for (float c : {1.f, 0.7f, 0.2f, 0.01f, -0.9f, -0.3f, -0.01f}) {
        Vec3 wo = dir(c, 0.9f);
        float r = thin_slab_reflectance(c, pane.eta);
        EXPECT_EQ(r, thin_slab_reflectance(-c, pane.eta));  // symmetric sheet
        const int n = 100000;
        Rng rng(52, 0);
        int n_refl = 0;
        for (int i = 0; i < n; ++i) {
            float uc = rng.next_1d();
            Vec2 u = next_2d(rng);
            auto s = bsdf_sample(pane, wo, uc, u, kRad);
            auto si = bsdf_sample(pane, wo, uc, u, kImp);
            ASSERT_TRUE(s && si);
            // Adjoint: no medium change, so no 1/eta^2 and the same sample in both modes.
            ASSERT_EQ(s->weight, si->weight);
            ASSERT_EQ(s->wi, si->wi);
            ASSERT_TRUE(s->is_delta());
            ASSERT_EQ(s->eta, 1.f);
            // Nothing of it has a density: the connections of BDPT and NEE see 0.
            ASSERT_EQ(bsdf_eval(pane, wo, s->wi, kRad), Rgb(0.f));
            ASSERT_EQ(bsdf_pdf_sa(pane, wo, s->wi, kRad), 0.f);
            if (s->lobe & kLobeReflection) {
                ++n_refl;
                ASSERT_EQ(s->pdf_sa, r);  // discrete probability
                ASSERT_EQ(s->weight, pane.specular_reflectance);
                ASSERT_EQ(s->wi, Vec3(-wo.x, -wo.y, wo.z));
            } else {
                ASSERT_TRUE(s->lobe & kLobeTransmission);
                ASSERT_NEAR(s->pdf_sa, 1 - r, 1e-7f);
                ASSERT_EQ(s->weight, pane.specular_transmittance);
                ASSERT_EQ(s->wi, -wo);  // straight through, no refraction offset
            }
            // Reverse discrete probability (pdf_rev): sampling back from wi picks the same lobe
            // with the same probability, since |wi.z| = |wo.z|.
            auto back = bsdf_sample(pane, s->wi, uc, u, kRad);
            ASSERT_TRUE(back);
            ASSERT_EQ(back->pdf_sa, s->pdf_sa);
            ASSERT_EQ(back->wi, wo);
        }
        double sd = std::sqrt(n * r * (1 - r)) + 0.5;
        EXPECT_NEAR(n_refl, n * r, 5 * sd) << "cos " << c;
        // Energy: the expected weight with white tints is R' + (1 - R') = 1, nothing absorbed.
    }
    ThinDielectricBsdf white;
    Rng rng(53, 0);
    double sum = 0;
    for (int i = 0; i < 10000; ++i) sum += bsdf_sample(white, dir(0.4f, 0.f), rng.next_1d(), {0, 0}, kRad)->weight.x;
    EXPECT_EQ(sum, 10000.0);
    EXPECT_TRUE(bsdf_is_delta_only(white));
    EXPECT_EQ(bsdf_lobes(white), kLobeReflection | kLobeTransmission | kLobeDelta);
}

TEST(BsdfProperties, NoNanOrInfAnywhere) {
    std::vector<Named> models = rough_models();
    for (float a : {1e-4f, 1e-2f, 1.f}) {
        models.push_back({"cond_ggx", conductor(MicrofacetType::GGX, a, a)});
        models.push_back({"cond_beck", conductor(MicrofacetType::Beckmann, a, 1.f)});
        models.push_back({"diel_ggx", dielectric(MicrofacetType::GGX, a, a)});
        models.push_back({"diel_beck", dielectric(MicrofacetType::Beckmann, a, a)});
    }
    for (float a : {1e-4f, 1e-2f, 1.f}) {
        models.push_back({"plastic_ggx", plastic(a)});
        models.push_back({"plastic_beck", plastic(a, MicrofacetType::Beckmann, true, {1, 1, 1})});
    }
    models.push_back({"smooth_plastic", plastic(0)});
    models.push_back({"smooth_plastic_white_nonlinear", plastic(0, MicrofacetType::GGX, true, {1, 1, 1}, 3.f)});
    models.push_back({"smooth_plastic_eta_lt_1", plastic(0, MicrofacetType::GGX, false, {1, 1, 1}, 0.7f)});
    models.push_back({"smooth_plastic_no_ks", [] {
                          PlasticBsdf p = plastic(0);
                          p.specular_reflectance = Rgb(0.f);
                          return p;
                      }()});
    models.push_back({"smooth_diel", DielectricBsdf{}});
    models.push_back({"thin_diel", ThinDielectricBsdf{}});
    models.push_back({"thin_diel_eta_lt_1", ThinDielectricBsdf{0.7f, {1, 1, 1}, {1, 1, 1}}});
    models.push_back({"smooth_cond", ConductorBsdf{}});
    models.push_back({"black", BlackBsdf{}});
    const float cosines[] = {0.f, 1e-7f, -1e-7f, 1e-4f, -1e-4f, 0.01f, -0.01f, 1.f, -1.f};
    const float us[] = {0.f, 1e-7f, 0.5f, 0.9999999f};
    Rng rng(61, 0);
    for (const Named& m : models) {
        for (int i = 0; i < 3000; ++i) {
            Vec3 wo = i < 9 * 16 ? dir(cosines[i % 9], 0.3f * float(i / 9)) : random_sphere_dir(rng);
            Vec2 u = i < 64 ? Vec2{us[i % 4], us[(i / 4) % 4]} : next_2d(rng);
            float uc = i < 64 ? us[(i / 16) % 4] : rng.next_1d();
            for (TransportMode mode : {kRad, kImp}) {
                auto s = bsdf_sample(m.bsdf, wo, uc, u, mode);
                if (wo.z == 0) { ASSERT_FALSE(s) << m.name; }
                if (s) {
                    ASSERT_TRUE(is_finite(s->weight) && is_finite(s->wi))
                        << m.name << " wo=(" << wo.x << "," << wo.y << "," << wo.z << ") u=(" << u.x << "," << u.y
                        << ") wi=(" << s->wi.x << "," << s->wi.y << "," << s->wi.z << ")";
                    ASSERT_TRUE(s->pdf_sa > 0 && std::isfinite(s->pdf_sa)) << m.name;
                    ASSERT_GE(min_component(s->weight), 0.f) << m.name;
                }
                Vec3 wi = random_sphere_dir(rng);
                if (i % 7 == 0) wi = dir(cosines[i % 9], 1.f);
                if (i % 11 == 0) wi = Vec3(-wo.x, -wo.y, wo.z);
                Rgb f = bsdf_eval(m.bsdf, wo, wi, mode);
                float p = bsdf_pdf_sa(m.bsdf, wo, wi, mode);
                ASSERT_TRUE(is_finite(f) && min_component(f) >= 0) << m.name << " wo.z=" << wo.z << " wi.z=" << wi.z;
                ASSERT_TRUE(std::isfinite(p) && p >= 0) << m.name;
                if (wo.z == 0 || wi.z == 0) {
                    ASSERT_TRUE(is_black(f)) << m.name;
                    ASSERT_EQ(p, 0.f) << m.name;
                }
            }
        }
    }
}

TEST(BsdfProperties, OneSidedDiffuseIsBlackFromBelow) {
    DiffuseBsdf one{{0.5f, 0.5f, 0.5f}, false}, two{{0.5f, 0.5f, 0.5f}, true};
    Vec3 wo = dir(-0.5f, 0.f), wi = dir(-0.7f, 2.f);
    EXPECT_TRUE(is_black(bsdf_eval(one, wo, wi, kRad)));
    EXPECT_FALSE(bsdf_sample(one, wo, 0.5f, {0.5f, 0.5f}, kRad));
    EXPECT_NEAR(bsdf_eval(two, wo, wi, kRad).x, 0.5f * kInvPi, 1e-7f);
    EXPECT_TRUE(is_black(bsdf_eval(two, wo, -wi, kRad)));  // opposite hemispheres
    auto s = bsdf_sample(two, wo, 0.5f, {0.5f, 0.5f}, kRad);
    ASSERT_TRUE(s);
    EXPECT_LT(s->wi.z, 0.f);
}

TEST(BsdfProperties, LobeFlags) {
    EXPECT_EQ(bsdf_lobes(DiffuseBsdf{}), kLobeReflection | kLobeDiffuse);
    EXPECT_EQ(bsdf_lobes(BlackBsdf{}), kLobeNone);
    EXPECT_EQ(bsdf_lobes(conductor(MicrofacetType::GGX, 0.1f, 0.1f)), kLobeReflection | kLobeGlossy);
    EXPECT_EQ(bsdf_lobes(ConductorBsdf{}), kLobeReflection | kLobeDelta);
    EXPECT_EQ(bsdf_lobes(DielectricBsdf{}), kLobeReflection | kLobeTransmission | kLobeDelta);
    EXPECT_TRUE(bsdf_has_nondelta(dielectric(MicrofacetType::GGX, 0.1f, 0.1f)));
    EXPECT_FALSE(bsdf_is_delta_only(BlackBsdf{}));
    // Smooth plastic: a mirror lobe (S to the classifier) and a substrate (D), both reachable.
    EXPECT_EQ(bsdf_lobes(plastic(0)), kLobeReflection | kLobeDiffuse | kLobeDelta);
    EXPECT_EQ(bsdf_lobes(plastic(0.1f)), kLobeReflection | kLobeDiffuse | kLobeGlossy);
    EXPECT_TRUE(bsdf_has_nondelta(plastic(0)));
    EXPECT_FALSE(bsdf_is_delta_only(plastic(0)));
}

// Integrators skip the lobe number of a BSDF that bsdf_sample_uses_uc() says ignores it (it gets
// 0): that must hold, or such a BSDF would always take one lobe. And one that reads it must be
// listed, or the skip would bias it.
TEST(BsdfProperties, UsesUcSaysWhichModelsReadTheLobeNumber) {
    std::vector<Named> models = rough_models();
    models.push_back({"smooth_conductor", ConductorBsdf{}});
    models.push_back({"smooth_dielectric", DielectricBsdf{}});
    models.push_back({"smooth_plastic", plastic(0)});
    models.push_back({"thin_dielectric", ThinDielectricBsdf{}});
    models.push_back({"black", BlackBsdf{}});
    for (const Named& m : models) {
        bool differs = false;
        for (int k = 0; k < 64 && !differs; ++k) {
            const Vec3 wo = dir(k % 2 ? 0.8f : -0.4f, 0.1f * float(k));
            const Vec2 u{(float(k) + 0.5f) / 64.f, float((k * 37) % 64) / 64.f};
            auto a = bsdf_sample(m.bsdf, wo, 0.f, u, kRad);
            for (float uc : {0.3f, 0.6f, 0.97f}) {
                auto b = bsdf_sample(m.bsdf, wo, uc, u, kRad);
                differs = differs || a.has_value() != b.has_value() || (a && (a->wi != b->wi || a->lobe != b->lobe));
            }
        }
        EXPECT_EQ(differs, bsdf_sample_uses_uc(m.bsdf)) << m.name;
    }
}

// ---- Plastic (Tungsten's model, plastic.cpp)

TEST(PlasticBsdf, InternalReflectanceByQuadrature) {
    // Tungsten's computeDiffuseFresnel(1.5) (10^6-point trapezoid) = 0.596346; total internal
    // reflection alone gives 1 - 1/eta^2 = 0.5556, a lower bound.
    EXPECT_NEAR(plastic_fdr_int(1.5f), 0.5963458f, 2e-6f);
    EXPECT_EQ(PlasticBsdf{}.fdr_int, plastic_fdr_int(PlasticBsdf{}.eta));  // the default is in step
    EXPECT_EQ(plastic_fdr_int(1.f), 0.f);
    for (float eta : {1.1f, 1.33f, 2.f, 3.f}) EXPECT_GT(plastic_fdr_int(eta), 1.f - 1.f / (eta * eta)) << eta;
    PlasticBsdf p;
    p.set_eta(1.33f);
    EXPECT_EQ(p.fdr_int, plastic_fdr_int(1.33f));
}

// With a white base the smooth coat loses nothing: F(mu_o) + (1 - F(mu_o)) (1 - Fdr_ext) /
// (eta^2 (1 - Fdr_int)) = 1, since 1 - Fdr_ext = eta^2 (1 - Fdr_int). Checked by deterministic
// quadrature of eval(), so it tests the 1/eta^2 scaling, the Fresnel factors and Fdr_int together
// to 1e-4 (a 1% error in any of them fails it).
TEST(PlasticBsdf, WhiteSmoothPlasticConservesEnergyExactly) {
    for (float eta : {1.5f, 1.2f, 2.4f, 0.8f})
        for (bool nonlinear : {false, true})
            for (float c : {1.f, 0.6f, 0.2f, 0.02f}) {
                PlasticBsdf p = plastic(0, MicrofacetType::GGX, nonlinear, {1, 1, 1}, eta);
                Vec3 wo = dir(c, 0.4f);
                // ∫ f cos dω over the hemisphere by the midpoint rule in mu^2 (dω cos = d(mu^2)/2 dphi).
                const int n = 4000;
                double sum = 0;
                for (int i = 0; i < n; ++i) {
                    float mu = std::sqrt((i + 0.5f) / n);
                    sum += bsdf_eval(p, wo, dir(mu, 1.f), kRad).x * kPiD / n;  // f is isotropic in phi
                }
                double albedo = fresnel_dielectric(c, eta).r + sum;
                EXPECT_NEAR(albedo, 1.0, 1e-4) << "eta " << eta << " cos " << c << " nonlinear " << nonlinear;
                // Sampling agrees: every sample's weight has mean 1.
                Albedo a = albedo_by_sampling(p, wo, kImp, 20000, 71);
                EXPECT_NEAR(a.mean.x, 1.f, 5 * a.std_err.x + 1e-4f);
            }
    // A grey base reflects less, and nonlinear (rho / (1 - rho Fdr)) less than linear (rho / (1 - Fdr)).
    Vec3 wo = dir(0.7f, 0.f), wi = dir(0.5f, 2.f);
    float lin = bsdf_eval(plastic(0, MicrofacetType::GGX, false, Rgb(0.5f)), wo, wi, kRad).x;
    float nl = bsdf_eval(plastic(0, MicrofacetType::GGX, true, Rgb(0.5f)), wo, wi, kRad).x;
    float fo = fresnel_dielectric(0.7f, 1.5f).r, fi = fresnel_dielectric(0.5f, 1.5f).r;
    float fdr = plastic_fdr_int(1.5f);
    EXPECT_NEAR(lin, (1 - fo) * (1 - fi) / 2.25f * 0.5f / (1 - fdr) / kPi, 1e-6f);
    EXPECT_NEAR(nl, (1 - fo) * (1 - fi) / 2.25f * 0.5f / (1 - 0.5f * fdr) / kPi, 1e-6f);
}

TEST(PlasticBsdf, SmoothMirrorLobeIsDiscrete) {
    PlasticBsdf p = plastic(0);
    p.specular_reflectance = {0.9f, 0.6f, 0.3f};
    const PlasticBsdf plain = plastic(0);
    const float ks = 0.6f;  // mean of specular_reflectance
    for (float c : {1.f, 0.5f, 0.1f, 0.01f, -0.4f}) {
        Vec3 wo = dir(c, 0.9f);
        float fo = fresnel_dielectric(std::abs(c), p.eta).r;
        float ps = fo * ks / (fo * ks + 1 - fo);  // Tungsten's lobe selection
        Rng rng(81, 0);
        const int n = 50000;
        int n_mirror = 0;
        for (int i = 0; i < n; ++i) {
            auto s = bsdf_sample(p, wo, rng.next_1d(), next_2d(rng), kRad);
            ASSERT_TRUE(s);
            if (s->is_delta()) {
                ++n_mirror;
                ASSERT_EQ(s->lobe, kLobeReflection | kLobeDelta);
                ASSERT_NEAR(s->pdf_sa, ps, 1e-6f);
                ASSERT_EQ(s->wi, reflect_local(wo));
                for (int k = 0; k < 3; ++k) ASSERT_NEAR(s->weight[k], fo * p.specular_reflectance[k] / ps, 1e-5f);
                // The delta lobe has no finite f: eval is the substrate alone, whatever Ks is.
                ASSERT_EQ(bsdf_eval(p, wo, s->wi, kRad), bsdf_eval(plain, wo, s->wi, kRad));
            } else {
                ASSERT_EQ(s->lobe, kLobeReflection | kLobeDiffuse);
                ASSERT_GT(s->wi.z * wo.z, 0.f);
                float pdf = bsdf_pdf_sa(p, wo, s->wi, kRad);
                ASSERT_TRUE(close_rel(pdf, s->pdf_sa, 1e-4));
                ASSERT_TRUE(close_rel(pdf, (1 - ps) * std::abs(s->wi.z) * kInvPi, 1e-4));
                Rgb expect = bsdf_eval(p, wo, s->wi, kRad) * (std::abs(s->wi.z) / s->pdf_sa);
                for (int k = 0; k < 3; ++k) ASSERT_TRUE(close_rel(expect[k], s->weight[k], 1e-4, 1e-7));
            }
        }
        double sd = std::sqrt(n * ps * (1 - ps)) + 0.5;
        EXPECT_NEAR(n_mirror, n * ps, 5 * sd) << "cos " << c;
        // Importance transport (light tracing, bdpt's light subpaths) makes the same choices with
        // the same weights: the coat has no refraction of its own to scale.
        for (float uc : {0.f, 0.5f * ps, 0.999f * ps, ps + 0.01f, 0.7f}) {
            auto r = bsdf_sample(p, wo, uc, {0.3f, 0.8f}, kRad), i = bsdf_sample(p, wo, uc, {0.3f, 0.8f}, kImp);
            ASSERT_TRUE(r && i);
            EXPECT_EQ(r->wi, i->wi);
            EXPECT_EQ(r->weight, i->weight);
            EXPECT_EQ(r->pdf_sa, i->pdf_sa);
            EXPECT_EQ(r->lobe, i->lobe);
        }
        // Exactly at the mirror direction eval and pdf hold the substrate only (no delta).
        Vec3 mirror = reflect_local(wo);
        EXPECT_NEAR(bsdf_pdf_sa(p, wo, mirror, kRad), (1 - ps) * std::abs(c) * kInvPi, 1e-6f);
    }
}

// A rough coat over a white base. Tungsten's model weights the base by the smooth coat's Fresnel,
// so it is not exactly energy conserving: it loses energy at grazing angles (the smooth coat
// transmits little there, the rough coat's reflection is masked: 0.14-0.8 at cos 0.01) and must
// never gain (measured maximum 1.0002 +- 0.0006). With a black base only the coat reflects.
TEST(PlasticBsdf, RoughPlasticEnergyBounded) {
    for (MicrofacetType t : {MicrofacetType::GGX, MicrofacetType::Beckmann})
        for (float a : {0.05f, 0.2f, 0.5f, 1.f})
            for (float c : {1.f, 0.5f, 0.1f, 0.01f}) {
                Albedo w = albedo_by_sampling(plastic(a, t, true, {1, 1, 1}), dir(c, 0.2f), kImp, 20000, 91);
                EXPECT_LE(w.mean.x, 1.001f + 4 * w.std_err.x) << a << " cos " << c;
                if (c >= 0.5f) {
                    EXPECT_GT(w.mean.x, 0.93f) << a << " cos " << c;
                }
                Albedo k = albedo_by_sampling(plastic(a, t, true, {0, 0, 0}), dir(c, 0.2f), kImp, 20000, 92);
                EXPECT_LE(k.mean.x, fresnel_dielectric(c, 1.5f).r + 0.1f) << a << " cos " << c;
                EXPECT_GE(k.mean.x, 0.f);
            }
}

TEST(PlasticBsdf, OneSidedIsBlackFromBelow) {
    for (float a : {0.f, 0.3f}) {
        PlasticBsdf one = plastic(a), two = plastic(a);
        one.two_sided = false;
        Vec3 wo = dir(-0.5f, 0.f), wi = dir(-0.7f, 2.f);
        EXPECT_TRUE(is_black(bsdf_eval(one, wo, wi, kRad)));
        EXPECT_EQ(bsdf_pdf_sa(one, wo, wi, kRad), 0.f);
        EXPECT_FALSE(bsdf_sample(one, wo, 0.5f, {0.5f, 0.5f}, kRad));
        EXPECT_EQ(bsdf_eval(two, wo, wi, kRad), bsdf_eval(two, -wo, -wi, kRad));
        EXPECT_TRUE(is_black(bsdf_eval(two, wo, -wi, kRad)));  // no transmission
        auto s = bsdf_sample(two, wo, 0.9f, {0.5f, 0.5f}, kRad);
        ASSERT_TRUE(s);
        EXPECT_LT(s->wi.z, 0.f);
    }
}

}  // namespace
}  // namespace omega
