#pragma once
// A small Pearson chi-square goodness-of-fit harness for the film tests (header-only so it
// cannot clash with a shared tests/support/chi2.h).
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

namespace omega::film_test {

// Regularized upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a): series below a + 1,
// Lentz's continued fraction above (Numerical Recipes 6.2), in long double.
inline double gamma_q(double a_, double x_) {
    const long double a = a_, x = x_;
    if (x <= 0) return 1.0;
    const long double log_pre = a * std::log(x) - x - std::lgamma(a);
    if (x < a + 1) {
        long double ap = a, sum = 1 / a, del = sum;
        for (int i = 0; i < 100000; ++i) {
            ap += 1;
            del *= x / ap;
            sum += del;
            if (std::abs(del) < std::abs(sum) * 1e-17L) break;
        }
        return double(1 - sum * std::exp(log_pre));
    }
    const long double tiny = 1e-300L;
    long double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
    for (int i = 1; i < 100000; ++i) {
        const long double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::abs(d) < tiny) d = tiny;
        c = b + an / c;
        if (std::abs(c) < tiny) c = tiny;
        d = 1 / d;
        const long double del = d * c;
        h *= del;
        if (std::abs(del - 1) < 1e-17L) break;
    }
    return double(std::exp(log_pre) * h);
}

struct Chi2Result {
    double statistic = 0;
    int dof = 0;
    double p_value = 0;
};

// Pearson's test of observed counts against expected counts. Bins expected to hold fewer than
// min_expected samples are pooled into one, as the statistic's chi-square law needs it; an
// observation in a bin with zero expectation fails outright (p = 0).
inline Chi2Result chi2_test(const std::vector<double>& observed, const std::vector<double>& expected,
                            double min_expected = 5.0) {
    Chi2Result r;
    double pooled_obs = 0, pooled_exp = 0;
    int bins = 0;
    for (size_t i = 0; i < observed.size(); ++i) {
        if (expected[i] == 0 && observed[i] > 0) return {std::numeric_limits<double>::infinity(), 0, 0.0};
        if (expected[i] < min_expected) {
            pooled_obs += observed[i];
            pooled_exp += expected[i];
            continue;
        }
        const double d = observed[i] - expected[i];
        r.statistic += d * d / expected[i];
        ++bins;
    }
    if (pooled_exp > 0) {
        const double d = pooled_obs - pooled_exp;
        r.statistic += d * d / pooled_exp;
        ++bins;
    }
    r.dof = bins - 1;
    r.p_value = r.dof > 0 ? gamma_q(r.dof / 2.0, r.statistic / 2.0) : 1.0;
    return r;
}

// Probability mass of pdf over each of nx * ny equal bins of [lo, hi]^2, by composite Simpson
// with sub x sub panels per bin (sub even). Independent of any sampler's analytic CDF.
inline std::vector<double> bin_masses_2d(const std::function<double(double, double)>& pdf, double lo, double hi,
                                         int nx, int ny, int sub = 16) {
    std::vector<double> mass(size_t(nx) * size_t(ny));
    const double hx = (hi - lo) / (double(nx) * sub), hy = (hi - lo) / (double(ny) * sub);
    // Nodes from one formula so the outermost land exactly on lo and hi: a density that jumps
    // to 0 at its support's edge must not be evaluated a rounding error outside it.
    auto node = [&](long k, long n) { return lo + (hi - lo) * (double(k) / double(n)); };
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            long double s = 0;
            for (int b = 0; b <= sub; ++b) {
                const double wy = (b == 0 || b == sub) ? 1 : (b % 2 ? 4 : 2);
                const double y = node(long(j) * sub + b, long(ny) * sub);
                for (int a = 0; a <= sub; ++a) {
                    const double wx = (a == 0 || a == sub) ? 1 : (a % 2 ? 4 : 2);
                    s += wx * wy * pdf(node(long(i) * sub + a, long(nx) * sub), y);
                }
            }
            mass[size_t(j) * nx + i] = double(s * hx * hy / 9.0);
        }
    return mass;
}

}  // namespace omega::film_test
