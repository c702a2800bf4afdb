#pragma once
// Unidirectional path tracer: the strategies s <= 1 of the path integral (camera subpath, with
// the last vertex either hit (s = 0) or connected to a light sample (s = 1)), combined with the
// power heuristic in solid-angle measure. max_depth counts edges (Veach's k): 1 = emitters seen
// directly, 2 = direct lighting.
#include <cstdint>

#include "integrator/lpe_tracker.h"
#include "sampling/sampler.h"
#include "scene/scene.h"

namespace omega {

// Unbounded depth still needs a hard stop for scenes that never absorb (a closed perfect mirror
// box): paths end after this many edges (the BDPT engine's subpaths after as many vertices).
constexpr int kMaxUnboundedDepth = 1 << 16;

struct PathTracerSettings {
    int max_depth = -1;  // -1: unbounded, Russian roulette ends paths (at most kMaxUnboundedDepth edges)
    int rr_depth = 5;    // first edge count at which Russian roulette may stop a path
    bool light_sampling = true;  // false: BSDF sampling only (IntegratorDesc::light_sampling)
};

// Per-thread counters; each worker owns one (cache-line aligned by its container).
struct TracerStats {
    uint64_t rays = 0;
    uint64_t samples = 0;
    uint64_t nonfinite = 0;
};

class PathTracer {
public:
    PathTracer(const Scene& scene, const PathTracerSettings& settings) : scene_(scene), settings_(settings) {}
    // Radiance along `ray`. Called concurrently from render threads; touches only `sampler` and
    // `stats` (and `lpe`). Bounce k draws from the camera-walk block of vertex k (see
    // sampling/sampler.h). With `lpe` (reset by the caller), every contribution is also offered
    // to the AOVs; the returned radiance is bit-identical either way.
    Rgb radiance(Ray ray, Sampler& sampler, TracerStats& stats, CameraLpeTracker* lpe = nullptr) const;

private:
    Rgb sample_direct(const SurfaceHit& hit, const Frame& shading, const Vec3& wo_local, const Bsdf& bsdf,
                      Sampler& sampler, TracerStats& stats) const;
    const Scene& scene_;
    PathTracerSettings settings_;
};

}  // namespace omega
