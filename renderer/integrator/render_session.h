#pragma once
// The render driver: progressive passes over tiles on a oneTBB arena.
//
// Lifecycle (Tungsten's): construct (prepare) -> run() (start; blocks) -> abort() from any thread.
// Determinism: sample i of pixel p draws from Sampler::make(sampler, seed, p, i) (its values depend
// only on (seed, p, i, dimension)) and each pixel belongs to exactly one tile, so the film is
// bit-identical for any thread count or tile order, and sample ranges merge exactly.
#include <atomic>
#include <functional>
#include <memory>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_arena.h>

#include "film/film.h"
#include "integrator/bdpt_tracer.h"
#include "integrator/path_tracer.h"
#include "integrator/strategy_images.h"
#include "scene/scene.h"

namespace omega {

struct RenderSettings {
    HaltDesc halt;           // none given: 64 spp
    int threads = 0;         // 0: all hardware threads
    uint64_t seed = 0;
    int tile_size = 32;
    long long first_sample = 0;  // resume: sample indices below this are already in the film
    IntegratorDesc integrator;
    int strategy_images_max_k = 0;  // > 0: record per-(s,t) images up to this path length (light, bdpt)
};

struct PassReport {
    int pass = 0;
    long long spp = 0;         // samples per pixel completed
    double elapsed_s = 0;
    double samples_per_s = 0;
    double rays_per_s = 0;
    uint64_t rays = 0, samples = 0, nonfinite = 0;
    uint64_t mis_errors = 0;  // MIS weights computed as non-finite (contribution dropped)
    ErrorEstimate error;
};

class RenderSession {
public:
    // Throws std::invalid_argument when the integrator is not available.
    RenderSession(const Scene& scene, const RenderSettings& settings);

    // Renders until the halt condition or abort(). Calls on_pass after each pass, on the calling
    // thread, while no worker touches the film. Returns the last report.
    PassReport run(const std::function<void(const PassReport&)>& on_pass = {});
    // Any thread: the current pass stops at the next tile boundary.
    void abort() { aborted_.store(true, std::memory_order_relaxed); }
    bool aborted() const { return aborted_.load(std::memory_order_relaxed); }

    const Film& film() const { return film_; }
    Film& film() { return film_; }
    const RenderSettings& settings() const { return settings_; }
    // Per-strategy images when settings().strategy_images_max_k > 0 (else null).
    const StrategyImages* strategy_images() const { return strategies_.get(); }

    // Strategies of the light and bdpt integrators the scene cannot use; see pathspace/classify.h.
private:
    void render_tile(const Rect& tile, long long s0, long long s1, TracerStats& stats);
    // Light tracing and BDPT: samples [s0, s1) of every pixel, one batch per sample index (splats
    // have no per-pixel sample count, so variance comes from the spread of batches).
    void render_pass_splatting(tbb::task_arena& arena, const std::vector<Rect>& tiles, long long s0, long long s1);
    // One batch of a splatting integrator: sample index i of every pixel, into the film.
    void render_sample_index(tbb::task_arena& arena, const std::vector<Rect>& tiles, long long i);

    const Scene& scene_;
    RenderSettings settings_;
    PathTracer tracer_;
    std::unique_ptr<BdptTracer> bdpt_;
    std::unique_ptr<StrategyImages> strategies_;
    tbb::enumerable_thread_specific<std::vector<StrategyContribution>> sample_strategies_;
    Film film_;
    tbb::enumerable_thread_specific<TracerStats> stats_;  // cache-aligned per thread
    tbb::enumerable_thread_specific<BdptScratch> scratch_;
    tbb::enumerable_thread_specific<std::vector<Splat>> sample_splats_;
    std::vector<Vec3d> batch_sums_;  // crop-sized, one batch's pixel sums (driver thread only)
    std::atomic<bool> aborted_{false};
};

// Number of worker threads `threads` resolves to (0 = hardware concurrency).
int resolve_threads(int threads);

}  // namespace omega
