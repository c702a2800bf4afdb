#pragma once
// Light tracing and BDPT splat across the whole film, so one batch's splats used to be merged
// on the driver thread alone: 10% of a BDPT render on 1 thread, and a serial section that caps
// the speedup on a many-core machine. Here the crop is cut into bands of rows; each tile's
// splats are copied, in their order, under every band their filter footprint reaches (by the
// worker that made them), and the bands are merged in parallel. A pixel belongs to one band and
// receives its splats in the serial order (tile order, then the order within a tile), so the
// sums are bit-identical to the serial merge and to any thread count.
//
// Concurrency: merge() and for_each_band() are called on the driver thread, inside nothing; the
// callbacks run on the arena's workers, never two at once for the same pixel. bucket() is
// const and writes only its `out`: any worker, one tile each.
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "film/film.h"
#include "film/filter.h"
#include "integrator/bdpt_tracer.h"
#include "integrator/ordered_dispatch.h"
#include "integrator/schedule_probe.h"

namespace omega {

// One tile's splats as SplatBands::bucket() lists them: those reaching band b are
// by_band[start[b] .. start[b + 1]), in the tile's order (a splat spanning two bands is in both).
// by_band only grows: entries past start.back() are stale, and resizing it for every tile of
// every batch value-initialised each new splat, a store per splat the copy then overwrote.
struct BandedSplats {
    std::vector<Splat> by_band;
    std::vector<uint32_t> start;  // bands() + 1 entries; empty for a tile that did not run
    void clear() { start.clear(); }
};

class SplatBands {
public:
    SplatBands(const Rect& crop, float filter_radius, int band_rows = kBandRows)
        : crop_(crop), radius_(filter_radius), rows_(std::max(1, band_rows)) {
        cut_rows(rows_);
    }

    size_t bands() const { return y0_.size() - 1; }
    // Rows [y0, y1) of band b, as a rect of the crop.
    Rect band(size_t b) const {
        Rect r = crop_;
        r.y0 = y0_[b];
        r.y1 = y0_[b + 1];
        return r;
    }

    // Driver thread, between batches (no bucket() or merge() in flight): cuts the bands again
    // for `workers`, from the splats the merges since the last call met in each band. A base
    // band (band_rows rows) that held a share s of them is split into ceil(s * workers) equal
    // parts, at most one a row, so no merge task is much more than one worker's share.
    // Where the light is in view, every light path splats onto its few rows: in the Cornell box
    // at 256x256 one 8-row band held 30% of the splats, and on 16 workers the merge waited for it
    // (schedule model: 16% of the time idle). Cut finer everywhere, the merge copies and clips
    // more splats (a tent footprint spans 2 rows; 1-row bands made light tracing 1.6% and 3.8%
    // slower on one thread), so only heavy bands are cut, and on 2 workers none that holds
    // under half. A splat counts once per band it reaches, so a split band's share grows a
    // little; the cap of one row bounds that. Which band a pixel is in never changes the order
    // of its additions, so the layout leaves the image's bits alone.
    void relayout(int workers) {
        uint64_t total = 0;
        std::vector<uint64_t> base((size_t(crop_.height()) + size_t(rows_) - 1) / size_t(rows_), 0);
        for (size_t b = 0; b < bands(); ++b) {
            base[size_t(y0_[b] - crop_.y0) / size_t(rows_)] += merged_[b];
            total += merged_[b];
        }
        if (total == 0) {
            // No counts yet (the first batch, or batches that splatted nothing): where bands
            // would be cut at all, the finest cut, a row each, as the counts would cut the
            // heaviest. On the base cut, the first batch's merge waited for the light's band
            // (Cornell light 256x256, schedule model @16: the merge's idle time 5.2% -> 3.1%),
            // and in a render of few batches that one is a large part. The cost, more copies
            // of the splats that span two rows, is paid for one batch.
            if (workers > 2 && bands() != size_t(std::max(0, crop_.height()))) cut_rows(1);
            return;
        }
        y0_.clear();
        for (size_t k = 0; k < base.size(); ++k) {
            const int a = crop_.y0 + int(k) * rows_, rows = std::min(rows_, crop_.y1 - a);
            const uint64_t parts = std::clamp<uint64_t>((base[k] * uint64_t(std::max(1, workers)) + total - 1) / total, 1,
                                                        uint64_t(rows));
            for (uint64_t p = 0; p < parts; ++p) y0_.push_back(a + int(uint64_t(rows) * p / parts));
        }
        y0_.push_back(crop_.y1);
        index_rows();
    }

    // Each band a task of its own region (bench only; see RenderSession::set_schedule_probe).
    void set_probe(ScheduleProbe* p) { probe_ = p; }

    // fn(band_rect) for every band, in parallel.
    template <class Fn>
    void for_each_band(tbb::task_arena& arena, Fn&& fn) const {
        for_each_index(arena, bands(), probe_, "bands", [&](size_t b) { fn(band(b)); });
    }

    // Any thread: lists one tile's splats (in their order) under every band their filter
    // footprint reaches, into `out`. The workers do this while a tile's splats are still in
    // their cache, so merge() reads each band's splats as contiguous runs: with pointers into
    // the tiles' lists, nearly every splat the merge read was a cache miss on a large film.
    void bucket(const std::vector<Splat>& splats, BandedSplats& out) const {
        const size_t n = bands();
        out.start.assign(n + 1, 0);
        // Counts shifted by one, so the prefix sums below turn them into each band's start.
        for (const Splat& sp : splats) {
            const auto [b0, b1] = band_span(sp);
            for (int b = b0; b <= b1; ++b) ++out.start[size_t(b) + 1];
        }
        for (size_t b = 0; b < n; ++b) out.start[b + 1] += out.start[b];
        if (out.by_band.size() < out.start[n]) out.by_band.resize(out.start[n]);
        // Each band's start serves as its write position, which then ends at the next band's
        // start; one shift puts the starts back.
        for (const Splat& sp : splats) {
            const auto [b0, b1] = band_span(sp);
            for (int b = b0; b <= b1; ++b) out.by_band[out.start[size_t(b)]++] = sp;
        }
        for (size_t b = n; b > 0; --b) out.start[b] = out.start[b - 1];
        out.start[0] = 0;
    }

    // fn(splat, x, y, filter_weight) for every crop pixel each splat of `tiles` (bucketed by
    // bucket(), in merge order) reaches. Each band's task also counts its splats, for relayout().
    template <class Fn>
    void merge(tbb::task_arena& arena, const Filter& filter, const std::vector<BandedSplats>& tiles, Fn&& fn) {
        // In band order, not heaviest first (integrator/ordered_dispatch.h): with 8-row bands
        // and the light in view, one band was a quarter of the merge, and on 16 workers the
        // merge waited for it in either order (schedule model: 15% and 13% idle), while on 2
        // cores the reordered merge ran 2-3% slower. relayout() cuts such a band instead.
        for_each_index(arena, bands(), probe_, "merge", [&](size_t b) {
            const Rect rows = band(b);
            for (const BandedSplats& t : tiles) {
                if (t.start.empty()) continue;  // a tile that did not run
                merged_[b] += t.start[b + 1] - t.start[b];
                for (uint32_t k = t.start[b], e = t.start[b + 1]; k < e; ++k) {
                    const Splat& sp = t.by_band[k];
                    for_each_filter_pixel(filter, rows, sp.film, [&](int x, int y, double f) { fn(sp, x, y, f); });
                }
            }
        });
    }

    static constexpr int kBandRows = 8;

private:
    Rect crop_;
    float radius_;
    int rows_;
    // The bands a splat's filter footprint reaches (b0 > b1: none), as for_each_filter_pixel
    // visits its rows. By table: an integer division per end of every splat, twice per bucket(),
    // was a tenth of bucket()'s time.
    std::pair<int, int> band_span(const Splat& sp) const {
        const auto [ya, yb] = filter_span(sp.film.y, radius_, crop_.y0, crop_.y1);
        if (ya > yb) return {1, 0};
        return {band_of_row_[size_t(ya - crop_.y0)], band_of_row_[size_t(yb - crop_.y0)]};
    }
    // Bands of `rows` rows each (the last one may be shorter).
    void cut_rows(int rows) {
        y0_.clear();
        for (int y = crop_.y0; y < crop_.y1; y += rows) y0_.push_back(y);
        y0_.push_back(std::max(crop_.y0, crop_.y1));
        index_rows();
    }
    void index_rows() {
        band_of_row_.assign(size_t(std::max(0, crop_.height())), 0);
        merged_.assign(bands(), 0);
        for (size_t b = 0; b < bands(); ++b)
            for (int y = y0_[b]; y < y0_[b + 1]; ++y) band_of_row_[size_t(y - crop_.y0)] = int(b);
    }
    std::vector<int> y0_;            // band b is rows [y0_[b], y0_[b + 1]); the last entry is crop_.y1
    std::vector<int> band_of_row_;   // crop row - crop_.y0 -> its band
    std::vector<uint64_t> merged_;   // splats merged per band since the last cut (band b's task writes b)
    ScheduleProbe* probe_ = nullptr;
};

}  // namespace omega
