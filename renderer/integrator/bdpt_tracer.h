#pragma once
// Per-thread tracer for the splatting integrators: bidirectional path tracing (every (s, t)
// strategy) and light tracing (t = 1 only), both over the path-space core in pathspace/.
// The same engine restricted to s <= 1 is the path tracer, used by tests to check the fast
// PathTracer against the general MIS routine.
#include <array>
#include <vector>

#include "integrator/bdpt_lpe.h"
#include "integrator/path_class.h"
#include "integrator/path_tracer.h"
#include "pathspace/classify.h"
#include "pathspace/connect.h"
#include "pathspace/lpe.h"

namespace omega {

// A t = 1 contribution: lands at a film position, on every pixel its filter reaches.
struct Splat {
    Vec2 film;
    Rgb value;  // already multiplied by the sensor importance; times the filter weight per pixel
    uint32_t aov_mask = 0;  // bit i: AOV i's expression matches this contribution's path
};

// Scratch owned by one worker thread.
struct BdptScratch {
    std::vector<PathVertex> camera, light;
    std::vector<LensCrossing> lens;  // t = 0
    ConnectStats connect;
    // With AOVs: the sample's subpaths through each AOV's automaton, and the camera-side
    // (t >= 2) sums per AOV of the last sample() (zeroed by it).
    BdptLpeMatcher lpe;
    std::array<Rgb, kMaxAovs> aov_camera{};
    // With the path-class breakdown: the last sample()'s camera-side contributions by class,
    // and the class of each splat it appended (in the same order); signature is scratch.
    std::vector<std::pair<PathClassKey, Rgb>> class_camera;
    std::vector<PathClassKey> splat_classes;
    uint64_t light_delta = 0, camera_delta = 0;  // bit i - 1: vertex i of the subpath is delta (path_class.h)
};

struct StrategyContribution {
    int s, t;
    Rgb unweighted, weighted;  // splats: already times the sensor importance
    bool splat;
    Vec2 film;
};

class BdptTracer {
public:
    // Concurrency: const after construction; sample() may run on any number of threads.
    BdptTracer(const Scene& scene, const IntegratorDesc& desc);
    // One sample for the pixel whose camera ray is `ray`. Returns the camera-side contribution
    // (strategies t >= 2) and appends the splats (t = 1, and t = 0 for a hittable lens). If `per_strategy` is
    // given, every strategy's contribution is also recorded there.
    Rgb sample(const Ray& ray, Sampler& sampler, TracerStats& stats, BdptScratch& scratch, std::vector<Splat>& splats,
               std::vector<StrategyContribution>* per_strategy = nullptr) const;

    // AOVs to match every contribution against (null: none); set before sampling starts. The
    // set must outlive the tracer's use. Splats then carry their match mask, and
    // scratch.aov_camera the camera-side values.
    void set_aovs(const LpeSet* aovs) { aovs_ = aovs && !aovs->empty() ? aovs : nullptr; }

    // The path-class breakdown (integrator/breakdown.h): classes up to this length (0: off);
    // set before sampling starts. scratch.class_camera and scratch.splat_classes then hold
    // each sample's contributions by class.
    void set_breakdown(int max_length) { breakdown_length_ = max_length; }

    const StrategySet& strategies() const { return set_; }
    const StrategyPlan& plan() const { return plan_; }
    // Whether sample() reads its camera ray: not for the light tracer, whose every strategy
    // starts at the light (t <= 1), so its driver need not make one.
    bool uses_camera_ray() const { return camera_limits_.max_vertices > 0; }

private:
    const Scene& scene_;
    StrategySet set_;
    StrategyPlan plan_;  // strategies that cannot contribute in this scene are never run
    int max_depth_;
    bool use_t0_ = false;  // light subpaths that hit the lens are a strategy here
    WalkLimits camera_limits_, light_limits_;
    std::shared_ptr<const PlanarMirrors> mirrors_;  // the connector's mirrors (set_.mirrors points here); null if none
    const LpeSet* aovs_ = nullptr;
    int breakdown_length_ = 0;
    // The breakdown's record of one contribution of strategy (s, t) (t = 0: the lens; via_mirror:
    // through the connector's mirror). Called on the sampling thread.
    void record_class(BdptScratch& scratch, int s, int t, bool via_mirror, bool splat, const Rgb& weighted) const;
};

}  // namespace omega
