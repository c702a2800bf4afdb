#include "integrator/strategy_images.h"

#include <cmath>
#include <string>

#include <fmt/format.h>

namespace omega {

StrategyImages::StrategyImages(const Rect& crop, int max_k, bool with_t0)
    : crop_(crop), max_k_(max_k), with_t0_(with_t0) {
    for (int k = 1; k <= max_k; ++k)
        for (int s = 0; s <= k + (with_t0 ? 1 : 0); ++s) strategies_.push_back({s, k + 1 - s});
    const size_t n = size_t(crop.area());
    weighted_.assign(strategies_.size(), std::vector<Vec3d>(n, Vec3d(0.0)));
    unweighted_.assign(strategies_.size(), std::vector<Vec3d>(n, Vec3d(0.0)));
}

int StrategyImages::index(int s, int t) const {
    const int k = s + t - 1;
    if (k < 1 || k > max_k_ || t < (with_t0_ ? 0 : 1)) return -1;
    // Strategies of length k start after those of lengths 1..k-1 (j + 1 each, j + 2 with t = 0).
    int base = 0;
    for (int j = 1; j < k; ++j) base += j + (with_t0_ ? 2 : 1);
    return base + s;
}

void StrategyImages::add_camera(int x, int y, const StrategyContribution& c) {
    int i = index(c.s, c.t);
    if (i < 0) return;
    size_t p = size_t(y - crop_.y0) * size_t(crop_.width()) + size_t(x - crop_.x0);
    weighted_[size_t(i)][p] += Vec3d(c.weighted);
    unweighted_[size_t(i)][p] += Vec3d(c.unweighted);
}

void StrategyImages::add_splat(const StrategyContribution& c, const Filter& filter, double scale) {
    int i = index(c.s, c.t);
    if (i < 0) return;
    for_each_filter_pixel(filter, crop_, c.film, [&](int x, int y, double f) {
        size_t p = size_t(y - crop_.y0) * size_t(crop_.width()) + size_t(x - crop_.x0);
        weighted_[size_t(i)][p] += Vec3d(c.weighted) * (f * scale);
        unweighted_[size_t(i)][p] += Vec3d(c.unweighted) * (f * scale);
    });
}

std::vector<ExrMeta::Layer> StrategyImages::layers(long long spp) const {
    std::vector<ExrMeta::Layer> out;
    const double inv = spp > 0 ? 1.0 / double(spp) : 0.0;
    for (size_t i = 0; i < strategies_.size(); ++i) {
        auto [s, t] = strategies_[i];
        for (int w = 0; w < 2; ++w) {
            const auto& src = w ? weighted_[i] : unweighted_[i];
            ExrMeta::Layer layer;
            layer.name = fmt::format("s{}t{}.{}", s, t, w ? "weighted" : "unweighted");
            layer.rgb.resize(src.size() * 3);
            for (size_t p = 0; p < src.size(); ++p)
                for (int k = 0; k < 3; ++k) layer.rgb[3 * p + size_t(k)] = float(src[p][k] * inv);
            out.push_back(std::move(layer));
        }
    }
    return out;
}

double StrategyImages::image_mean(int s, int t, bool weighted, long long spp) const {
    int i = index(s, t);
    if (i < 0 || spp <= 0) return 0;
    const auto& src = weighted ? weighted_[size_t(i)] : unweighted_[size_t(i)];
    double sum = 0;
    for (const Vec3d& v : src) sum += (v.x + v.y + v.z) / 3.0;
    return sum / double(src.size()) / double(spp);
}

}  // namespace omega
