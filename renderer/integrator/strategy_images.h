#pragma once
// Debug output in the manner of pbrt's visualizestrategies: for each BDPT strategy (s, t) with
// path length k = s + t - 1 <= max_k, the unweighted contribution (the strategy alone, an
// unbiased estimate of all paths of length k it can sample) and the MIS-weighted one (its share
// of the final image). Plain sums over all samples; normalised when the layers are taken.
//
// Concurrency: add_camera() on pixel p from the thread that owns p's tile; add_splat() only
// from the ordered splat merge (one thread); layers() after rendering.
#include <vector>

#include "film/film.h"
#include "film/filter.h"
#include "integrator/bdpt_tracer.h"

namespace omega {

class StrategyImages {
public:
    // with_t0: also the strategies t = 0 (light subpaths hitting a lens of finite aperture).
    StrategyImages(const Rect& crop, int max_k, bool with_t0 = false);
    int max_k() const { return max_k_; }
    void add_camera(int x, int y, const StrategyContribution& c);
    // `scale` turns one light path's splat into its share of a pixel (1 / crop pixels).
    void add_splat(const StrategyContribution& c, const Filter& filter, double scale);
    // Layers "s{s}t{t}.weighted" and "s{s}t{t}.unweighted", divided by the samples per pixel.
    std::vector<ExrMeta::Layer> layers(long long spp) const;
    // Image mean (channel average) of one strategy's layer, for tests.
    double image_mean(int s, int t, bool weighted, long long spp) const;

private:
    int index(int s, int t) const;  // -1 if not recorded
    Rect crop_;
    int max_k_;
    bool with_t0_;
    std::vector<std::pair<int, int>> strategies_;
    std::vector<std::vector<Vec3d>> weighted_, unweighted_;
};

}  // namespace omega
