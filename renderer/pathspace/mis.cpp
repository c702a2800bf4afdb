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

double mis_weight(const FullPathPdfs& path, int s, const StrategySet& set) {
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
