#pragma once
// `omega converge SCENE [--reference REF.exr | --no-reference] [--integrators path,bdpt,light] [--budget 60] [--runs 3]`:
// error against a reference (or, with --no-reference, the estimated relative variance) at
// log-spaced render times, per integrator, as CSV files and a log-log PNG plot. See docs/converge.md.
// `omega compare IMAGE REF`: the same error measures for one image.
#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

namespace omega {

struct ConvergeArgs {
    std::string scene;
    std::string reference;
    std::vector<std::string> integrators{"path"};
    std::string sampler;  // sobol | independent for the runs; empty: the scene's
    double budget_s = 60;
    int runs = 3;
    std::string out_dir;
    int threads = 0;
    uint64_t seed = 0;
    std::optional<int> width, height;
    std::optional<double> reference_time_s;
    // No reference at all: each checkpoint reports the image's own estimated relative variance
    // (from the film's per-pixel variance, the EXR's var.* channels) instead of an error.
    bool no_reference = false;
    std::vector<std::string> defines;
    // --breakdown: error per path class (client/converge_breakdown.h), for this many classes.
    bool breakdown = false;
    int breakdown_classes = 6;
};

struct CompareArgs {
    std::string image, reference;
    std::string filter = "tent";
};

void add_converge_command(CLI::App& app, ConvergeArgs& args);
int run_converge(const ConvergeArgs& args);
void add_compare_command(CLI::App& app, CompareArgs& args);
int run_compare(const CompareArgs& args);

// Error of an image against a reference (both RGB float, same size).
struct ImageError {
    double rmse = 0;    // sqrt(mean over pixels and channels of (x - r)^2)
    double relmse = 0;  // mean of (x - r)^2 / (r^2 + eps)
    double mape = 0;    // mean of |x - r| / (|r| + eps)
    double mean_ratio = 0;  // mean(x) / mean(r)
};
constexpr double kRelMseEps = 0.01;
// relvar = mean over pixels and channels of var / max(mean, eps)^2. eps = 0.1 puts the
// denominator on relMSE's scale (r^2 + 0.01), so the two modes read alike for an unbiased render.
constexpr double kRelVarEps = 0.1;

// Log-spaced checkpoints 1, 2, 4, ... below budget, then budget itself.
std::vector<double> converge_times(double budget_s);
// Least-squares slope of log(y) against log(x) over positive pairs; NaN with fewer than 2.
double loglog_slope(const std::vector<double>& x, const std::vector<double>& y);

}  // namespace omega
