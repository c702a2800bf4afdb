// The furnace at albedo 0.999 with Russian roulette as the only way paths end (no depth cap),
// sampled by BSDF sampling alone (IntegratorDesc::light_sampling = false).
//
// Closed form. Camera inside a closed diffuse sphere of albedo rho emitting Le (two-sided).
// With rr_depth = 1, every bounce is followed by roulette with survival q = throughput = rho, after
// which the throughput is 1 again. Emitters hit count with weight 1 (no light sampling), so a path
// returns Le * N, N the number of surface vertices it visits, and P(N >= n) = rho^(n-1):
// N is geometric with success probability p = 1 - rho, so
//   E[L]   = Le / (1 - rho),
//   Var[L] = Le^2 rho / (1 - rho)^2,
//   mu_4   = Var^2 (9 + p^2 / (1 - p))       (excess kurtosis of the geometric law: 6 + p^2/(1-p)).
// The film's per-pixel variance estimate s^2 = n * var_of_mean is unbiased for Var[L], and over P
// independent pixels of n samples its mean has variance (mu_4 - Var^2 (n-3)/(n-1)) / (n P).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "stability_util.h"

namespace omega {
namespace {

struct VarianceCheck {
    double mean = 0, s2 = 0;            // image mean; mean over pixels of the per-sample variance estimate
    double z_mean = 0, z_var = 0;       // against the closed forms
    double var_expected = 0, s2_se = 0;  // closed-form variance and standard error of s2
    double s2_se_empirical = 0;          // the same from the spread of s2 over pixels
};

VarianceCheck check(const test::RenderResult& r, double rho, double le, long long spp, double var_scale = 1.0) {
    const Film& f = r.film();
    Rect c = f.crop();
    double sum_s2 = 0, sum_s2sq = 0, sum_m = 0;
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            PixelStats p = f.pixel(x, y);
            // Gray scene: the three channels are the same numbers; use one.
            double s2 = p.var_of_mean.x * double(p.n);
            sum_s2 += s2;
            sum_s2sq += s2 * s2;
            sum_m += p.mean.x;
        }
    const double P = double(c.area()), n = double(spp);
    VarianceCheck v;
    v.mean = sum_m / P;
    v.s2 = sum_s2 / P;
    const double pr = 1.0 - rho;
    const double mu = le / pr, var = le * le * rho / (pr * pr);
    v.var_expected = var * var_scale;
    const double mu4 = var * var * (9.0 + pr * pr / rho);
    v.s2_se = std::sqrt((mu4 - var * var * (n - 3) / (n - 1)) / n / P);
    v.s2_se_empirical = std::sqrt(std::max(0.0, sum_s2sq / P - v.s2 * v.s2) / (P - 1));
    v.z_mean = (v.mean - mu) / std::sqrt(var / (n * P));
    v.z_var = (v.s2 - v.var_expected) / v.s2_se;
    return v;
}

SceneDesc bsdf_only_furnace(float rho, float le) {
    SceneDesc d = stability::sphere_furnace(rho, le, 16);
    d.integrator.max_depth = -1;  // no depth cap: roulette ends every path
    d.integrator.rr_depth = 1;    // roulette after every bounce, survival = rho
    d.integrator.light_sampling = false;
    // The closed forms for the spread of s^2 assume i.i.d. samples in a pixel; Sobol' samples of
    // one pixel are negatively correlated (that is their point), so this test pins `independent`.
    d.integrator.sampler = SamplerType::Independent;
    return d;
}

class FurnaceVariance : public ::testing::TestWithParam<float> {};

TEST_P(FurnaceVariance, MeanAndPerSampleVarianceMatchClosedForm) {
    const float rho = GetParam();
    const float le = 1e-3f;
    const long long spp = 64;
    auto r = test::render(bsdf_only_furnace(rho, le), spp, 21);
    stability::expect_finite(r, "furnace");
    VarianceCheck v = check(r, double(rho), double(le), spp);
    const double bound = test::z_threshold(2 * 3);  // mean and variance, three albedos
    EXPECT_LT(std::abs(v.z_mean), bound) << "rho " << rho << " mean " << v.mean << " expected " << le / (1.0 - double(rho));
    EXPECT_LT(std::abs(v.z_var), bound) << "rho " << rho << " s2 " << v.s2 << " expected " << v.var_expected;
    std::printf("[ stability ] furnace rho=%.3f: mean %.6g (expected %.6g, z %.2f), s2 %.6g (expected %.6g, z %.2f, "
                "se %.3g closed-form / %.3g empirical), %.2f s, %.3g rays\n",
                double(rho), v.mean, double(le) / (1.0 - double(rho)), v.z_mean, v.s2, v.var_expected, v.z_var,
                v.s2_se, v.s2_se_empirical, r.report.elapsed_s, double(r.report.rays));
    // The standard error used above is itself right: the closed-form one agrees with the spread
    // of s2 over pixels (a loose factor: a sample standard deviation of heavy-tailed values).
    EXPECT_GT(v.s2_se_empirical, 0.5 * v.s2_se);
    EXPECT_LT(v.s2_se_empirical, 2.0 * v.s2_se);
}

INSTANTIATE_TEST_SUITE_P(Albedo, FurnaceVariance, ::testing::Values(0.5f, 0.9f, 0.999f));

// The test can fail: a variance 15% off is rejected, and so is the mean of a different albedo.
TEST(FurnaceVarianceSanity, DetectsAWrongVariance) {
    const float rho = 0.999f, le = 1e-3f;
    const long long spp = 64;
    auto r = test::render(bsdf_only_furnace(rho, le), spp, 22);
    VarianceCheck v = check(r, double(rho), double(le), spp, 1.15);
    EXPECT_GT(std::abs(v.z_var), test::z_threshold(1)) << "s2 " << v.s2 << " vs " << v.var_expected;
    VarianceCheck w = check(r, 0.998, double(le), spp);
    EXPECT_GT(std::abs(w.z_mean), test::z_threshold(1));
}

// Light sampling off is a path-integrator switch only; the splatting integrators refuse it.
TEST(FurnaceVariance, LightSamplingSwitchIsPathOnly) {
    for (IntegratorType t : {IntegratorType::Light, IntegratorType::Bdpt}) {
        SceneDesc d = bsdf_only_furnace(0.5f, 1.f);
        d.integrator.type = t;
        EXPECT_THROW(test::render(d, 1, 1), std::invalid_argument) << stability::name_of(t);
    }
}

}  // namespace
}  // namespace omega
