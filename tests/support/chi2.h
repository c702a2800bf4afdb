#pragma once
// Chi-square goodness-of-fit tests for samplers (after Mitsuba's ChiSquareTest): histogram many
// samples over a grid, integrate the claimed density over each cell, pool sparse cells and compare.
// Everything is deterministic for a given seed.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "math/vec.h"
#include "sampling/rng.h"

namespace omega::test {

struct Chi2Result {
    bool passed = false;
    double statistic = 0;
    int dof = 0;
    double p_value = 0;
    double threshold = 0;      // per-test significance after the Sidak correction
    double pdf_integral = 0;   // integral of the density over the whole domain
    size_t samples = 0, valid_samples = 0;
    size_t pdf_mismatches = 0; // samples whose claimed pdf is <= 0 or disagrees with the pdf function
    std::string message;       // human-readable summary (and the reason for a failure)
};

// Regularized upper incomplete gamma Q(a, x) = Γ(a, x) / Γ(a) (series + Lentz continued fraction).
double gamma_q(double a, double x);
// P(X >= statistic) for X ~ chi-square with dof degrees of freedom.
double chi2_p_value(double statistic, int dof);
// Per-test level so that the family of test_count tests rejects falsely with probability significance.
double sidak_threshold(double significance, int test_count);

// Pearson test from raw counts: cells expecting fewer than min_expected samples are pooled;
// a sample in a cell whose expected count is 0 is an immediate failure.
Chi2Result chi2_from_counts(const std::vector<double>& observed, const std::vector<double>& expected,
                            double significance, int test_count, double min_expected = 5.0);

struct Chi2Options {
    size_t sample_count = 1'000'000;
    double significance = 0.01;
    int test_count = 1;          // size of the family of tests, for the Sidak correction
    uint64_t seed = 7;
    int subdivisions = 3;        // Gauss-Legendre pieces per cell and axis
    // Relative tolerance between a sample's claimed pdf and the pdf function.
    double pdf_rel_tol = 2e-3;
    // Fraction of samples allowed to disagree (float round-off near singular configurations).
    double pdf_mismatch_fraction = 1e-4;
};

// One line on stdout per test, so measured p-values show up in test logs.
void print_result(const std::string& label, const Chi2Result& r);

struct DirSample {
    Vec3 w;
    double pdf_sa = 0;  // the density the sampler claims for w
};
using DirSampler = std::function<std::optional<DirSample>(omega::Rng&)>;
using DirPdfSa = std::function<double(const Vec3&)>;

// Grid over (cos theta, phi) in [-1, 1] x [0, 2 pi): dω = dcosθ dφ, so pdf_sa integrates directly.
// Samples the sampler returns as nullopt form an extra "absorbed" cell with mass 1 - ∫pdf.
Chi2Result chi2_sphere(const DirSampler& sampler, const DirPdfSa& pdf_sa, const Chi2Options& opt,
                       int res_cos = 64, int res_phi = 128);

struct PointSample {
    Vec2 p;
    double pdf_area = 0;
};
using PointSampler = std::function<std::optional<PointSample>(omega::Rng&)>;
using PointPdfArea = std::function<double(Vec2)>;

struct PlaneDomain {
    double x0, y0, x1, y1;
};
Chi2Result chi2_plane(const PointSampler& sampler, const PointPdfArea& pdf_area, PlaneDomain domain,
                      const Chi2Options& opt, int res_x = 64, int res_y = 64);

}  // namespace omega::test
