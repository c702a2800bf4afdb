#pragma once
// The render driver: progressive passes over tiles on a oneTBB arena.
//
// Lifecycle (Tungsten's): construct (prepare) -> run() (start; blocks) -> abort() from any thread.
// Determinism: sample i of pixel p draws from Sampler::make(sampler, seed, p, i) (its values depend
// only on (seed, p, i, dimension)) and each pixel belongs to exactly one tile, so the film is
// bit-identical for any thread count or tile order, and sample ranges merge exactly.
#include <atomic>
#include <chrono>
#include <functional>
#include <optional>
#include <memory>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_arena.h>

#include "film/film.h"
#include "film/zeroed_array.h"
#include "integrator/aov_images.h"
#include "integrator/bdpt_tracer.h"
#include "integrator/breakdown_collector.h"
#include "integrator/ordered_dispatch.h"
#include "integrator/path_tracer.h"
#include "integrator/schedule_probe.h"
#include "integrator/splat_bands.h"
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
    // The measurement-contribution breakdown by path class (integrator/breakdown.h); none: off,
    // and the render runs exactly the code it runs without it. Its passes are never cut at a
    // time limit (a cut pass would weigh some pixels' samples more than others').
    std::optional<BreakdownDesc> breakdown;
    // When halt.time_s starts counting (default: when run() starts). `omega render` passes its own
    // start, so that loading the scene is inside the budget the user gave.
    std::optional<std::chrono::steady_clock::time_point> time_origin;
    // What time limits read (null: steady_clock::now). Tests inject a deterministic clock; it is
    // called from the worker threads, once per tile.
    std::function<std::chrono::steady_clock::time_point()> clock;
};

struct PassReport {
    int pass = 0;
    long long spp = 0;         // samples per pixel completed
    double elapsed_s = 0;
    double samples_per_s = 0;
    double rays_per_s = 0;
    uint64_t rays = 0, samples = 0, nonfinite = 0;
    uint64_t mis_errors = 0;  // MIS weights computed as non-finite (contribution dropped)
    // The pass was cut at the time limit: tiles not started by then got none of its samples, so
    // some pixels hold more than `spp` (the film's per-pixel counts keep every mean unbiased).
    bool cut = false;
    ErrorEstimate error;
};

class RenderSession {
public:
    // Throws std::invalid_argument when the integrator is not available.
    RenderSession(const Scene& scene, const RenderSettings& settings);
    // What the constructor refuses, without allocating a film (the daemon checks every submit).
    static void check_settings(const RenderSettings& settings);

    // Renders until the halt condition or abort(). Calls on_pass after each pass, on the calling
    // thread, while no worker touches the film. Returns the last report.
    PassReport run(const std::function<void(const PassReport&)>& on_pass = {});
    // Any thread: the current pass stops at the next tile boundary.
    void abort() { aborted_.store(true, std::memory_order_relaxed); }
    bool aborted() const { return aborted_.load(std::memory_order_relaxed); }

    // Path tracing: called on the worker thread that rendered `tile`, as soon as the tile holds
    // samples [0, spp) of its pass, while other tiles are still rendering; it may read the
    // tile's pixels (nothing else of the film). Light tracing and BDPT splat across tiles, so a
    // tile is only final at the pass boundary: they never call it. Set before run().
    using TileFn = std::function<void(const Rect& tile, long long spp)>;
    void set_on_tile(TileFn fn) { on_tile_ = std::move(fn); }

    // Runs each tile's work, on the worker threads: the daemon shares its threads between jobs
    // through it (daemon/thread_share.h). Null: the work runs directly. Set before run().
    using TileRunner = std::function<void(const std::function<void()>& work)>;
    void set_tile_runner(TileRunner r) { tile_runner_ = std::move(r); }

    // Bench only (bench/throughput): records this run's parallel regions and the duration of
    // each task, to predict its speedup on more cores (integrator/schedule_probe.h). The record
    // means something only when tasks do not overlap: throws std::logic_error unless the session
    // runs on one thread. The caller brackets run() with p->start() and p->stop(). Set before run().
    void set_schedule_probe(ScheduleProbe* p);

    const Film& film() const { return film_; }
    Film& film() { return film_; }
    const RenderSettings& settings() const { return settings_; }
    // Per-strategy images when settings().strategy_images_max_k > 0 (else null).
    const StrategyImages* strategy_images() const { return strategies_.get(); }

    // Light path expression outputs of the scene's film (`aov`), null when it names none.
    // Read like film(): between passes.
    const AovImages* aovs() const { return aovs_.get(); }
    AovImages* aovs() { return aovs_.get(); }

    // The breakdown of the samples rendered by this session (settings().breakdown), null when
    // off. Read between passes, like film().
    const BreakdownCollector* breakdown() const { return breakdown_.get(); }
    BreakdownCollector* breakdown() { return breakdown_.get(); }

private:
    void render_tile(const Rect& tile, long long s0, long long s1, TracerStats& stats);
    // Any thread: whether a tile may still start in this pass (false once the pass is cut).
    bool tile_may_start();
    // Light tracing and BDPT: samples [s0, s1) of every pixel, one batch per sample index (splats
    // have no per-pixel sample count, so variance comes from the spread of batches). Returns the
    // end of the batches that reached every pixel (s1 unless the pass was cut).
    long long render_pass_splatting(tbb::task_arena& arena, const std::vector<Rect>& tiles, long long s0, long long s1);
    // One batch of a splatting integrator: sample index i of every pixel, into the film.
    void render_sample_index(tbb::task_arena& arena, const std::vector<Rect>& tiles, long long i);
    // Driver thread, after a pass: the film's error, its chunks summed on the arena's workers.
    ErrorEstimate estimate_error(tbb::task_arena& arena);

    const Scene& scene_;
    RenderSettings settings_;
    PathTracer tracer_;
    std::unique_ptr<BdptTracer> bdpt_;
    std::unique_ptr<StrategyImages> strategies_;
    std::unique_ptr<AovImages> aovs_;
    std::unique_ptr<BreakdownCollector> breakdown_;
    tbb::enumerable_thread_specific<std::vector<StrategyContribution>> sample_strategies_;
    Film film_;
    tbb::enumerable_thread_specific<TracerStats> stats_;  // cache-aligned per thread
    tbb::enumerable_thread_specific<BdptScratch> scratch_;
    tbb::enumerable_thread_specific<std::vector<Splat>> tile_raw_splats_;  // one tile's, before bucketing (its samples append to it)
    std::unique_ptr<SplatBands> bands_;  // light tracing and BDPT: the crop's row bands
    std::vector<BandedSplats> banded_tiles_;  // one wave's splats by tile and band (driver thread sizes it)
    // Each tile's cost in its last pass or batch (workers record their own tiles), so the next
    // one starts the longest first; wave_order_ is a wave's share of that order (driver thread).
    LongestFirst tile_costs_;
    std::vector<uint32_t> wave_order_;
    std::vector<Film::ErrorPart> error_parts_;  // estimate_error()'s chunk sums (driver thread sizes it)
    // Crop-sized, one batch's camera estimates and light-path splats (allocated and cleared by
    // the driver thread, cleared band by band in parallel). Zeroed pages: a value-initialised
    // vector was written whole by the driver thread alone, every page a fault, before the first
    // batch could start (light tracing's first pass ran 25% slower than its others).
    ZeroedArray<Vec3d> batch_sums_;
    ZeroedArray<Vec3d> batch_splats_;
    std::atomic<bool> aborted_{false};
    TileFn on_tile_;
    TileRunner tile_runner_;
    ScheduleProbe* probe_ = nullptr;  // bench only, one thread: see set_schedule_probe
    void run_tile(const std::function<void()>& work) const {
        if (tile_runner_) tile_runner_(work);
        else work();
    }
    // Time limit of the current pass: set by run() on the driver thread before the pass starts,
    // read by the workers. A pass may be cut only when every pixel already has a sample.
    std::optional<std::chrono::steady_clock::time_point> cut_at_;
    std::atomic<bool> pass_cut_{false};
    std::chrono::steady_clock::time_point now() const {
        return settings_.clock ? settings_.clock() : std::chrono::steady_clock::now();
    }
};

// Number of worker threads `threads` resolves to (0 = hardware concurrency).
int resolve_threads(int threads);

}  // namespace omega
