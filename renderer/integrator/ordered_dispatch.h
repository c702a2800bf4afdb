#pragma once
// Parallel work handed out in a chosen order, each item to the next worker that asks, and the
// order itself: longest first, by each item's cost the last time it ran.
//
// Why not tbb::parallel_for over the items: its range splitting runs them in no useful order, so
// the region's barrier waits for whichever long item happened to start last. A pass over a
// 256x256 image has 64 tiles, 4 per worker on 16 threads. bench/throughput's schedule model
// (integrator/schedule_probe.h; Cornell box, path, 16 spp) put the idle time at that barrier at
// 8-9% of 16 workers' time with tiles started in index order, and at 3% with the longest first
// by the last pass (Graham's LPT rule): a predicted speedup of 13.9 became 14.8. Splat bands are
// not reordered: see SplatBands::merge.
// The order changes only which worker runs an item and when, never what it computes or where
// its result goes, so images stay bit-identical.
//
// Concurrency: for_each_ordered() is called by the driver thread; fn runs on the arena's workers,
// each item once. LongestFirst is driver-only, except record(), which workers call for distinct
// items during a region (order() reads the costs only between regions).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <numeric>
#include <vector>

#include "integrator/schedule_probe.h"

namespace omega {

// fn(i) for every i in [0, n), in parallel in TBB's order (items of similar cost, or ones whose
// order gained nothing: the splat bands, the film's error chunks). With a probe, one region of
// `kind` with a task per item (bench only; see RenderSession::set_schedule_probe).
template <class Fn>
void for_each_index(tbb::task_arena& arena, size_t n, ScheduleProbe* probe, const char* kind, Fn&& fn) {
    if (probe) probe->region_begin(kind);
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                ScheduleProbe::TaskTimer timer(probe, uint32_t(i));
                fn(i);
            }
        });
    });
    if (probe) probe->region_end();
}

// fn(item) for every item of `order`, in that order of starting; fn returns false to stop its
// worker taking more (a pass cut at its time limit), and the others stop at their next item.
template <class Fn>
void for_each_ordered(tbb::task_arena& arena, const std::vector<uint32_t>& order, Fn&& fn) {
    std::atomic<size_t> next{0};
    std::atomic<bool> stop{false};
    arena.execute([&] {
        // One task per worker slot; a slot that starts after the queue is empty does nothing.
        tbb::parallel_for(
            0, std::max(1, arena.max_concurrency()),
            [&](int) {
                while (!stop.load(std::memory_order_relaxed)) {
                    const size_t i = next.fetch_add(1, std::memory_order_relaxed);
                    if (i >= order.size()) return;
                    if (!fn(order[i])) {
                        stop.store(true, std::memory_order_relaxed);
                        return;
                    }
                }
            },
            tbb::simple_partitioner());
    });
}

// Items ordered by what they cost when they last ran, longest first; items never run, in index
// order after them (the first pass: index order).
class LongestFirst {
public:
    void resize(size_t n) {
        if (cost_.size() != n) cost_.assign(n, -1.0);
    }
    // A worker: item i took `cost` (seconds per sample) this time.
    void record(size_t i, double cost) { cost_[i] = cost; }
    const std::vector<uint32_t>& order() {
        order_.resize(cost_.size());
        std::iota(order_.begin(), order_.end(), 0u);
        std::stable_sort(order_.begin(), order_.end(), [&](uint32_t a, uint32_t b) { return cost_[a] > cost_[b]; });
        return order_;
    }

private:
    std::vector<double> cost_;
    std::vector<uint32_t> order_;
};

}  // namespace omega
