#include "pathspace/mis.h"

#include <cmath>

namespace omega {

bool strategy_possible(const FullPathPdfs& path, int s) {
    const int k = path.k();
    const int t = k + 1 - s;
    if (s < 0 || t < 0) return false;
    if (t == 0) return path.sensor_hittable;
    if (s == 0) return path.light_hittable;
    // Light tracing never joins a vertex at infinity to the sensor (connect() refuses it), so the
    // path k = 1 from the environment straight into the lens has no s = 1 strategy.
    if (s == 1 && t == 1 && path.light_at_infinity) return false;
    // The connecting edge v_{s-1} -- v_s: neither end may be a delta scattering event.
    return !path.delta[size_t(s - 1)] && !path.delta[size_t(s)];
}

namespace {

bool has_connector(const FullPathPdfs& path, int j, const StrategySet& set) {
    const int k = path.k();
    return j >= 1 && j < k && size_t(j) < path.connector.size() && path.connector[size_t(j)] > 0 &&
           set.allows_connector(j, k - j);
}

// Sum over every strategy that can produce the path, ordinary and connector, of (p / p_base)^2:
// the base is strategy s = `base`, or the connector through v_base. The ratios walk outwards
// from the base one vertex at a time; a connector c_j is reached from the ordinary strategy
// next to it (p_c / p_{j-1} = pL[j-1] / (pS[j-1] pS[j] J_j), p_c / p_{j+2} = pS[j+1] /
// (pL[j] pL[j+1] J_j)), so no density is divided out that the product does not hold: a zero
// density on one side makes its ratios 0 or infinite, never 0/0.
double ratio_square_sum(const FullPathPdfs& path, int base, bool base_is_connector, const StrategySet& set) {
    const int k = path.k();
    const auto& pL = path.p_light;
    const auto& pS = path.p_sensor;
    double sum = 0;
    auto ordinary = [&](int si, double r) {
        if (strategy_possible(path, si) && set.allows(si, k + 1 - si)) sum += r * r;
    };
    auto is_other_connector = [&](int j) { return has_connector(path, j, set) && !(base_is_connector && j == base); };
    int up = base, down = base;
    double r_up = 1.0, r_down = 1.0;
    if (base_is_connector) {
        sum += 1.0;
        const double J = path.connector[size_t(base)];
        r_down = pS[size_t(base)] * J;    // p_base / p_c
        r_up = pL[size_t(base)] * J;      // p_{base+1} / p_c
        up = base + 1;
        ordinary(base, r_down);
    }
    ordinary(up, r_up);
    double r = r_up;
    for (int i = up; i <= k; ++i) {
        if (is_other_connector(i + 1)) {  // c_{i+1} from p_i
            const double rc = r * pL[size_t(i)] / (pS[size_t(i)] * pS[size_t(i + 1)] * path.connector[size_t(i + 1)]);
            sum += rc * rc;
        }
        r *= pL[size_t(i)] / pS[size_t(i)];
        ordinary(i + 1, r);
    }
    r = r_down;
    for (int i = down; i >= 1; --i) {
        if (is_other_connector(i - 2)) {  // c_{i-2} from p_i
            const double rc = r * pS[size_t(i - 1)] / (pL[size_t(i - 2)] * pL[size_t(i - 1)] * path.connector[size_t(i - 2)]);
            sum += rc * rc;
        }
        r *= pS[size_t(i - 1)] / pL[size_t(i - 1)];
        ordinary(i - 1, r);
    }
    return sum;
}

double checked(double w) { return std::isfinite(w) && w >= 0 ? w : -1.0; }

}  // namespace

double mis_weight_connector(const FullPathPdfs& path, int j, const StrategySet& set) {
    if (!has_connector(path, j, set)) return -1.0;
    return checked(1.0 / ratio_square_sum(path, j, true, set));
}

double mis_weight(const FullPathPdfs& path, int s, const StrategySet& set) {
    // With a connector vertex on the path, its strategy joins the sum.
    if (!path.connector.empty()) return checked(1.0 / ratio_square_sum(path, s, false, set));
    const int k = path.k();
    double sum = 1.0;  // (p_s / p_s)^2
    // Towards more light vertices: r_{i+1} = r_i * p_light[i] / p_sensor[i].
    double r = 1.0;
    for (int i = s; i <= k; ++i) {
        r *= path.p_light[size_t(i)] / path.p_sensor[size_t(i)];
        const int si = i + 1;
        if (strategy_possible(path, si) && set.allows(si, k + 1 - si)) sum += r * r;
    }
    // Towards fewer light vertices: r_{i-1} = r_i * p_sensor[i-1] / p_light[i-1].
    r = 1.0;
    for (int i = s; i >= 1; --i) {
        r *= path.p_sensor[size_t(i - 1)] / path.p_light[size_t(i - 1)];
        const int si = i - 1;
        if (strategy_possible(path, si) && set.allows(si, k + 1 - si)) sum += r * r;
    }
    double w = 1.0 / sum;
    if (!std::isfinite(w) || !(w >= 0)) return -1.0;
    return w;
}

}  // namespace omega
