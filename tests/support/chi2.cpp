#include "chi2.h"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <numeric>
#include <sstream>

namespace omega::test {

namespace {
// Series for the lower function P(a, x); converges quickly for x < a + 1.
double gamma_p_series(double a, double x) {
    double sum = 1.0 / a, term = sum, ap = a;
    for (int n = 0; n < 100000; ++n) {
        ap += 1;
        term *= x / ap;
        sum += term;
        if (std::abs(term) < std::abs(sum) * 1e-15) break;
    }
    return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

// Modified Lentz continued fraction for Q(a, x); converges quickly for x > a + 1.
double gamma_q_cf(double a, double x) {
    constexpr double kTiny = 1e-300;
    double b = x + 1 - a, c = 1 / kTiny, d = 1 / b, h = d;
    for (int i = 1; i < 100000; ++i) {
        double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::abs(d) < kTiny) d = kTiny;
        c = b + an / c;
        if (std::abs(c) < kTiny) c = kTiny;
        d = 1 / d;
        double delta = d * c;
        h *= delta;
        if (std::abs(delta - 1) < 1e-15) break;
    }
    return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

std::string summary(const Chi2Result& r) {
    std::ostringstream os;
    os << "chi2=" << r.statistic << " dof=" << r.dof << " p=" << r.p_value << " (threshold " << r.threshold
       << ") pdf_integral=" << r.pdf_integral << " valid=" << r.valid_samples << "/" << r.samples
       << " pdf_mismatches=" << r.pdf_mismatches;
    return os.str();
}

bool pdf_agrees(double claimed, double actual, double rel_tol) {
    if (!(claimed > 0)) return false;
    return std::abs(claimed - actual) <= rel_tol * std::max(std::abs(claimed), std::abs(actual)) + 1e-9;
}

// 3x3-point Gauss-Legendre over a rectangle. The rule is open (no node on the boundary), so
// densities that jump exactly at a cell boundary (hemispheres, cone edges) integrate exactly.
template <class F>
double gauss3x3(F& f, double x0, double x1, double y0, double y1) {
    static const double kNode[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
    static const double kWeight[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
    double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1), hx = 0.5 * (x1 - x0), hy = 0.5 * (y1 - y0), sum = 0;
    for (int b = 0; b < 3; ++b)
        for (int a = 0; a < 3; ++a) sum += kWeight[a] * kWeight[b] * f(cx + hx * kNode[a], cy + hy * kNode[b]);
    return sum * hx * hy;
}

// Adaptive refinement by quadrants: sharp lobes (low roughness, grazing incidence) need far finer
// sampling than the rest of the domain, and a fixed rule overestimates their mass.
template <class F>
double integrate_adaptive(F& f, double x0, double x1, double y0, double y1, double whole, double tol, int depth) {
    double xm = 0.5 * (x0 + x1), ym = 0.5 * (y0 + y1);
    double q[4] = {gauss3x3(f, x0, xm, y0, ym), gauss3x3(f, xm, x1, y0, ym), gauss3x3(f, x0, xm, ym, y1),
                   gauss3x3(f, xm, x1, ym, y1)};
    double fine = q[0] + q[1] + q[2] + q[3];
    if (depth <= 0 || std::abs(fine - whole) <= tol) return fine;
    return integrate_adaptive(f, x0, xm, y0, ym, q[0], 0.25 * tol, depth - 1) +
           integrate_adaptive(f, xm, x1, y0, ym, q[1], 0.25 * tol, depth - 1) +
           integrate_adaptive(f, x0, xm, ym, y1, q[2], 0.25 * tol, depth - 1) +
           integrate_adaptive(f, xm, x1, ym, y1, q[3], 0.25 * tol, depth - 1);
}

// Integrates f over every cell of a res_x x res_y grid, each cell split into sub x sub pieces that
// are refined adaptively until the mass error is far below one sample's worth.
template <class F>
std::vector<double> integrate_cells(F&& f, double x0, double x1, double y0, double y1, int res_x, int res_y, int sub,
                                    double abs_tol) {
    int nx = res_x * sub, ny = res_y * sub;
    double hx = (x1 - x0) / nx, hy = (y1 - y0) / ny;
    std::vector<double> cells(size_t(res_x) * res_y, 0.0);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            double ax = x0 + i * hx, ay = y0 + j * hy;
            double whole = gauss3x3(f, ax, ax + hx, ay, ay + hy);
            cells[size_t(j / sub) * res_x + size_t(i / sub)] +=
                integrate_adaptive(f, ax, ax + hx, ay, ay + hy, whole, abs_tol, 7);
        }
    return cells;
}

// Adds the absorbed cell, runs the test and fills the sampling bookkeeping.
Chi2Result finish(std::vector<double> observed, const std::vector<double>& cell_integrals, size_t valid,
                  size_t invalid, size_t mismatches, const Chi2Options& opt) {
    double n = double(opt.sample_count);
    double total = std::accumulate(cell_integrals.begin(), cell_integrals.end(), 0.0);
    std::vector<double> expected(cell_integrals.size());
    for (size_t i = 0; i < expected.size(); ++i) expected[i] = std::max(0.0, cell_integrals[i]) * n;
    observed.push_back(double(opt.sample_count - valid));
    expected.push_back(std::max(0.0, 1.0 - total) * n);
    Chi2Result r = chi2_from_counts(observed, expected, opt.significance, opt.test_count);
    r.pdf_integral = total;
    r.samples = opt.sample_count;
    r.valid_samples = valid;
    r.pdf_mismatches = mismatches;
    std::string reason;
    if (invalid > 0) reason = "sampler returned a non-finite pdf or an invalid point / direction; ";
    if (double(mismatches) > opt.pdf_mismatch_fraction * n) reason += "claimed pdf disagrees with pdf function; ";
    if (!reason.empty()) r.passed = false;
    // Keep the specific reason from the counting stage (e.g. a sample in a zero-mass cell).
    std::string detail = r.dof == 0 && !r.passed ? "; " + r.message : "";
    r.message = reason + summary(r) + detail;
    return r;
}
}  // namespace

void print_result(const std::string& label, const Chi2Result& r) {
    std::printf("[chi2] %-48s %s %s\n", label.c_str(), r.passed ? "PASS" : "FAIL", r.message.c_str());
}

double gamma_q(double a, double x) {
    if (x <= 0) return 1.0;
    if (x < a + 1) return std::clamp(1.0 - gamma_p_series(a, x), 0.0, 1.0);
    return std::clamp(gamma_q_cf(a, x), 0.0, 1.0);
}

double chi2_p_value(double statistic, int dof) {
    if (dof <= 0) return 1.0;
    return gamma_q(0.5 * dof, 0.5 * statistic);
}

double sidak_threshold(double significance, int test_count) {
    return 1.0 - std::pow(1.0 - significance, 1.0 / std::max(1, test_count));
}

Chi2Result chi2_from_counts(const std::vector<double>& observed, const std::vector<double>& expected,
                            double significance, int test_count, double min_expected) {
    Chi2Result r;
    r.threshold = sidak_threshold(significance, test_count);
    std::vector<size_t> order(observed.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });

    double total_obs = std::accumulate(observed.begin(), observed.end(), 0.0);
    double pooled_obs = 0, pooled_exp = 0;
    double stat = 0;
    int cells = 0;
    for (size_t idx : order) {
        double o = observed[idx], e = expected[idx];
        // A handful of samples in a zero-density cell can be integration round-off; many cannot.
        if (e == 0 && o > std::max(1.0, 1e-5 * total_obs)) {
            r.passed = false;
            std::ostringstream os;
            os << "cell " << idx << " has " << o << " samples but zero expected mass";
            r.message = os.str();
            return r;
        }
        if (e < min_expected) {
            pooled_obs += o;
            pooled_exp += e;
        } else if (pooled_exp > 0 && pooled_exp < min_expected) {
            // Fold an under-full pool into the first well-populated cell.
            o += pooled_obs;
            e += pooled_exp;
            pooled_obs = pooled_exp = 0;
            stat += (o - e) * (o - e) / e;
            ++cells;
        } else {
            stat += (o - e) * (o - e) / e;
            ++cells;
        }
    }
    if (pooled_exp >= min_expected) {
        stat += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / pooled_exp;
        ++cells;
    } else if (pooled_exp > 0 && pooled_obs > min_expected + 10 * std::sqrt(min_expected)) {
        // Nowhere to fold: only happens when almost all mass is pooled, so compare loosely.
        stat += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / std::max(pooled_exp, 1.0);
        ++cells;
    }
    r.statistic = stat;
    r.dof = cells - 1;
    r.p_value = chi2_p_value(stat, r.dof);
    r.passed = r.dof <= 0 ? (stat == 0) : r.p_value >= r.threshold;
    if (r.dof <= 0 && stat == 0) r.p_value = 1;
    r.message = summary(r);
    return r;
}

Chi2Result chi2_sphere(const DirSampler& sampler, const DirPdfSa& pdf_sa, const Chi2Options& opt, int res_cos,
                       int res_phi) {
    const double two_pi = 2.0 * kPiD;
    auto dir = [](double z, double phi) {
        double s = std::sqrt(std::max(0.0, 1.0 - z * z));
        return Vec3(float(s * std::cos(phi)), float(s * std::sin(phi)), float(z));
    };
    std::vector<double> cells =
        integrate_cells([&](double z, double phi) { return pdf_sa(dir(z, phi)); }, -1, 1, 0, two_pi, res_cos,
                        res_phi, opt.subdivisions,
                        0.01 / double(opt.sample_count));
    // cells are stored [phi][cos]; integrate_cells indexes as x = cos, y = phi.
    std::vector<double> observed(cells.size(), 0.0);
    Rng rng(opt.seed, 0);
    size_t valid = 0, invalid = 0, mismatches = 0;
    for (size_t s = 0; s < opt.sample_count; ++s) {
        std::optional<DirSample> d = sampler(rng);
        if (!d) continue;
        const Vec3& w = d->w;
        if (!is_finite(w) || !std::isfinite(d->pdf_sa) ||
            std::abs(length(Vec3d(w)) - 1.0) > 1e-3) {
            ++invalid;
            continue;
        }
        ++valid;
        if (!pdf_agrees(d->pdf_sa, pdf_sa(w), opt.pdf_rel_tol)) ++mismatches;
        double z = std::clamp(double(w.z), -1.0, 1.0);
        double phi = std::atan2(double(w.y), double(w.x));
        if (phi < 0) phi += two_pi;
        int ci = std::clamp(int((z + 1) * 0.5 * res_cos), 0, res_cos - 1);
        int pi = std::clamp(int(phi / two_pi * res_phi), 0, res_phi - 1);
        observed[size_t(pi) * res_cos + ci] += 1;
    }
    return finish(std::move(observed), cells, valid, invalid, mismatches, opt);
}

Chi2Result chi2_plane(const PointSampler& sampler, const PointPdfArea& pdf_area, PlaneDomain domain, const Chi2Options& opt,
                      int res_x, int res_y) {
    std::vector<double> cells = integrate_cells(
        [&](double x, double y) { return pdf_area(Vec2{float(x), float(y)}); }, domain.x0, domain.x1, domain.y0,
        domain.y1, res_x, res_y, opt.subdivisions, 0.01 / double(opt.sample_count));
    std::vector<double> observed(cells.size(), 0.0);
    Rng rng(opt.seed, 0);
    size_t valid = 0, invalid = 0, mismatches = 0;
    for (size_t s = 0; s < opt.sample_count; ++s) {
        std::optional<PointSample> d = sampler(rng);
        if (!d) continue;
        Vec2 p = d->p;
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(d->pdf_area) || p.x < domain.x0 || p.x > domain.x1 ||
            p.y < domain.y0 || p.y > domain.y1) {
            ++invalid;
            continue;
        }
        ++valid;
        if (!pdf_agrees(d->pdf_area, pdf_area(p), opt.pdf_rel_tol)) ++mismatches;
        int ix = std::clamp(int((p.x - domain.x0) / (domain.x1 - domain.x0) * res_x), 0, res_x - 1);
        int iy = std::clamp(int((p.y - domain.y0) / (domain.y1 - domain.y0) * res_y), 0, res_y - 1);
        observed[size_t(iy) * res_x + ix] += 1;
    }
    return finish(std::move(observed), cells, valid, invalid, mismatches, opt);
}

}  // namespace omega::test
