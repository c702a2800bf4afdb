#pragma once
// Discrete distribution over n items by weight (light selection, triangle selection by area).
#include <cstddef>
#include <cstdint>
#include <vector>

namespace omega {

class DiscreteDistribution {
public:
    DiscreteDistribution() = default;
    explicit DiscreteDistribution(const std::vector<double>& weights);

    bool empty() const { return pmf_.empty(); }
    size_t size() const { return pmf_.size(); }
    double total() const { return total_; }
    float pmf(size_t i) const { return pmf_[i]; }
    // Returns an index and rescales u to [0,1) for reuse.
    size_t sample(float u, float* u_remapped = nullptr) const {
        // A scene's one light: index 0, as the search would return, without the call.
        if (pmf_.size() == 1 && !u_remapped) return 0;
        return search(u, u_remapped);
    }

private:
    size_t search(float u, float* u_remapped) const;

    std::vector<float> pmf_;
    std::vector<double> cdf_;  // cdf_[i] = P(index < i+1), last entry exactly 1
    double total_ = 0;
};

}  // namespace omega
