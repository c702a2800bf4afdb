#pragma once
// Unidirectional path tracer: the strategies s <= 1 of the path integral (camera subpath, with
// the last vertex either hit (s = 0) or connected to a light sample (s = 1)), combined with the
// power heuristic in solid-angle measure. max_depth counts edges (Veach's k): 1 = emitters seen
// directly, 2 = direct lighting.
#include <cstdint>
#include <memory>

#include "integrator/lpe_tracker.h"
#include "integrator/path_class.h"
#include "sampling/sampler.h"
#include "scene/scene.h"

namespace omega {

struct PlanarMirrors;  // pathspace/mirror_connector.h

// Unbounded depth still needs a hard stop for scenes that never absorb (a closed perfect mirror
// box): paths end after this many edges (the BDPT engine's subpaths after as many vertices).
constexpr int kMaxUnboundedDepth = 1 << 16;

struct PathTracerSettings {
    int max_depth = -1;  // -1: unbounded, Russian roulette ends paths (at most kMaxUnboundedDepth edges)
    int rr_depth = 5;    // first edge count at which Russian roulette may stop a path
    bool light_sampling = true;  // false: BSDF sampling only (IntegratorDesc::light_sampling)
    // Next-event estimation through planar mirrors (pathspace/mirror_connector.h). Off only for
    // tests that check the connector's MIS against the plain path tracer.
    bool mirror_connector = true;
};

// Per-thread counters; each worker owns one (cache-line aligned by its container).
struct TracerStats {
    uint64_t rays = 0;
    uint64_t samples = 0;
    uint64_t nonfinite = 0;
};

class PathTracer {
public:
    PathTracer(const Scene& scene, const PathTracerSettings& settings);
    // Radiance along `ray`. Called concurrently from render threads; touches only `sampler` and
    // `stats` (and `lpe`). Bounce k draws from the camera-walk block of vertex k (see
    // sampling/sampler.h). With `lpe` (reset by the caller), every contribution is also offered
    // to the AOVs; with `classes` (reset by the caller), to the path-class breakdown. The
    // returned radiance is bit-identical either way.
    Rgb radiance(Ray ray, Sampler& sampler, TracerStats& stats, CameraLpeTracker* lpe = nullptr,
                 PathClassTracker* classes = nullptr) const;

private:
    // Next-event estimation in two halves: the draws (a light and a point on it), then the light
    // sample, the BSDF and the shadow ray. radiance() takes the BSDF sample between them (see there).
    struct DirectDraw {
        const Light* light = nullptr;  // null: no light, or one facing away (nothing to evaluate)
        float pmf = 0;                 // its selection probability
        Vec2 u;
    };
    DirectDraw draw_direct(const SurfaceHit& hit, Sampler& sampler, const Vec2* ahead) const;
    Rgb eval_direct(const DirectDraw& d, const SurfaceHit& hit, const Frame& shading, const Vec3& wo_local,
                    const Bsdf& bsdf, TracerStats& stats) const;
    // Next-event estimation through each planar mirror from camera-walk vertex k (k edges before it).
    Rgb sample_direct_via_mirrors(const SurfaceHit& hit, const Frame& shading, const Vec3& wo_local, const Bsdf& bsdf,
                                  int k, Sampler& sampler, TracerStats& stats) const;
    const Scene& scene_;
    PathTracerSettings settings_;
    // The scene's planar mirrors (pathspace/mirror_connector.h): next-event estimation also
    // samples lights through each of them; empty when the scene has none, or without light sampling.
    std::shared_ptr<const PlanarMirrors> mirrors_;
};

}  // namespace omega
