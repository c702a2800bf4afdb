#include "sampling/distribution.h"

#include <algorithm>

namespace omega {

DiscreteDistribution::DiscreteDistribution(const std::vector<double>& weights) {
    double sum = 0;
    for (double w : weights) sum += std::max(0.0, w);
    total_ = sum;
    if (weights.empty() || !(sum > 0)) return;
    pmf_.resize(weights.size());
    cdf_.resize(weights.size());
    double acc = 0;
    for (size_t i = 0; i < weights.size(); ++i) {
        double p = std::max(0.0, weights[i]) / sum;
        pmf_[i] = float(p);
        acc += p;
        cdf_[i] = acc;
    }
    cdf_.back() = 1.0;
}

size_t DiscreteDistribution::search(float u, float* u_remapped) const {
    // The first entry above u (upper_bound), clamped to the last. Most distributions here are a
    // light's few triangles or a scene's few lights: counting the entries not above u (the cdf
    // is non-decreasing, so that is the same entry) has no branch to mispredict, where a
    // rectangle light's two triangles made the search's branch a coin flip per light sample.
    const double ud = double(u);
    size_t i = 0;
    if (cdf_.size() <= 8) {
        for (size_t j = 0; j + 1 < cdf_.size(); ++j) i += !(cdf_[j] > ud);
    } else {
        auto it = std::upper_bound(cdf_.begin(), cdf_.end(), ud);
        i = size_t(std::min<ptrdiff_t>(it - cdf_.begin(), ptrdiff_t(cdf_.size()) - 1));
    }
    // Never return a zero-probability item.
    while (pmf_[i] == 0 && i > 0) --i;
    if (u_remapped) {
        double lo = i == 0 ? 0.0 : cdf_[i - 1];
        double w = cdf_[i] - lo;
        *u_remapped = w > 0 ? std::min(float((double(u) - lo) / w), 0x1.fffffep-1f) : 0.f;
    }
    return i;
}

}  // namespace omega
