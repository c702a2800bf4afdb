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
#include <array>
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
        : crop_(crop), radius_(filter_radius), rows_(std::max(1, band_rows)),
          block_(std::max(1, (crop.width() + kBlocks - 1) / kBlocks)),
          min_strip_(4 * std::max(1, int(std::ceil(2.f * filter_radius)))) {
        cut_rows(rows_);
    }

    size_t bands() const { return x0_.size(); }
    // Band b: a rect of the crop, all of its row group's rows, a strip of its columns.
    Rect band(size_t b) const {
        const size_t g = size_t(group_of_band_[b]);
        const bool last = b + 1 == size_t(group_first_[g + 1]);
        return Rect{x0_[b], gy0_[g], last ? crop_.x1 : x0_[b + 1], gy0_[g + 1]};
    }

    // Driver thread, between batches (no bucket() or merge() in flight): cuts the bands again
    // for `workers`, from the splats the merges since the last call met in each band.
    // - Rows: a base band (band_rows rows) that held a share s of them is split into
    //   ceil(s * workers) row groups of equal height, at most one a row. Where the light is in
    //   view, every light path splats onto its few rows: in the Cornell box at 256x256 one 8-row
    //   band held 30% of the splats, and on 16 workers the merge waited for it (schedule model:
    //   16% of the time idle). Cut finer everywhere, the merge copies and clips more splats (a
    //   tent footprint spans 2 rows; 1-row bands made light tracing 1.6% and 3.8% slower on one
    //   thread), so only heavy bands are cut, and on 2 workers none that holds under half.
    // - Columns, beyond 2 workers: each row group is cut into strips of about equal counts (from
    //   where its splats fell along the rows), ceil(its share * kStripsPerWorker * workers) of
    //   them, no narrower than min_strip_. Tasks of a worker's share still left a worker's share
    //   idle at the merge's end (Cornell light 256x256, model @16: 3.2% of the time), and a
    //   strip copies only the splats that straddle its edges, a few in a hundred.
    // A splat counts once per band it reaches, so a split band's share grows a little. Which
    // band a pixel is in never changes the order of its additions, so the layout leaves the
    // image's bits alone.
    void relayout(int workers) {
        const uint64_t w = uint64_t(std::max(1, workers));
        uint64_t total = 0;
        for (uint64_t m : merged_) total += m;
        count_columns_ = workers > 2;
        if (total == 0) {
            // No counts yet (the first batch, or batches that splatted nothing): where bands
            // would be cut at all, the finest cut of rows, a row each, as the counts would cut
            // the heaviest. On the base cut, the first batch's merge waited for the light's band
            // (Cornell light 256x256, schedule model @16: the merge's idle time 5.2% -> 3.1%),
            // and in a render of few batches that one is a large part. The cost, more copies
            // of the splats that span two rows, is paid for one batch.
            if (workers > 2) cut_rows(1);
            return;
        }
        std::vector<uint64_t> base((size_t(crop_.height()) + size_t(rows_) - 1) / size_t(rows_), 0);
        for (size_t b = 0; b < bands(); ++b) base[size_t(band(b).y0 - crop_.y0) / size_t(rows_)] += merged_[b];
        Layout next;
        for (size_t k = 0; k < base.size(); ++k) {
            const int a = crop_.y0 + int(k) * rows_, rows = std::min(rows_, crop_.y1 - a);
            const uint64_t parts = std::clamp<uint64_t>((base[k] * w + total - 1) / total, 1, uint64_t(rows));
            for (uint64_t p = 0; p < parts; ++p) {
                const int y0 = a + int(uint64_t(rows) * p / parts), y1 = a + int(uint64_t(rows) * (p + 1) / parts);
                next.add_group(y0, crop_.x0);
                if (!count_columns_) continue;
                double count = 0;
                std::array<double, kBlocks> hist{};
                counted_in(y0, y1, count, hist);
                const double strips = std::ceil(count * double(w * kStripsPerWorker) / double(total));
                cut_columns(hist, uint64_t(std::min(strips, double(kBlocks))), next);
            }
        }
        next.gy0.push_back(crop_.y1);
        next.group_first.push_back(int(next.x0.size()));
        apply(std::move(next));
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
        for (const Splat& sp : splats) for_each_band_of(sp, [&](int b) { ++out.start[size_t(b) + 1]; });
        for (size_t b = 0; b < n; ++b) out.start[b + 1] += out.start[b];
        if (out.by_band.size() < out.start[n]) out.by_band.resize(out.start[n]);
        // Each band's start serves as its write position, which then ends at the next band's
        // start; one shift puts the starts back.
        for (const Splat& sp : splats) for_each_band_of(sp, [&](int b) { out.by_band[out.start[size_t(b)]++] = sp; });
        for (size_t b = n; b > 0; --b) out.start[b] = out.start[b - 1];
        out.start[0] = 0;
    }

    // fn(splat, x, y, filter_weight) for every crop pixel each splat of `tiles` (bucketed by
    // bucket(), in merge order) reaches.
    // Each band's task also counts its splats for relayout(), and beyond 2 workers, where they
    // fall along the rows.
    template <class Fn>
    void merge(tbb::task_arena& arena, const Filter& filter, const std::vector<BandedSplats>& tiles, Fn&& fn) {
        // In band order, not heaviest first (integrator/ordered_dispatch.h): with 8-row bands
        // and the light in view, one band was a quarter of the merge, and on 16 workers the
        // merge waited for it in either order (schedule model: 15% and 13% idle), while on 2
        // cores the reordered merge ran 2-3% slower. relayout() cuts such a band instead.
        for_each_index(arena, bands(), probe_, "merge", [&](size_t b) {
            const Rect r = band(b);
            uint64_t* hist = count_columns_ ? &xhist_[b * kBlocks] : nullptr;
            for (const BandedSplats& t : tiles) {
                if (t.start.empty()) continue;  // a tile that did not run
                merged_[b] += t.start[b + 1] - t.start[b];
                for (uint32_t k = t.start[b], e = t.start[b + 1]; k < e; ++k) {
                    const Splat& sp = t.by_band[k];
                    if (hist) ++hist[block_of(sp.film.x)];
                    for_each_filter_pixel(filter, r, sp.film, [&](int x, int y, double f) { fn(sp, x, y, f); });
                }
            }
        });
    }

    static constexpr int kBandRows = 8;
    // Beyond 2 workers a band's splats are counted in this many blocks of columns, where
    // relayout() may cut it, into strips of about 1 / (kStripsPerWorker * workers) of a batch.
    static constexpr int kBlocks = 64;
    static constexpr uint64_t kStripsPerWorker = 4;

private:
    // A cut of the crop: row groups (group g is rows [gy0[g], gy0[g + 1])), each of bands
    // group_first[g] .. group_first[g + 1] - 1, band b the columns [x0[b], the next band's x0 or
    // the crop's right edge). The last entries of gy0 and group_first close the last group.
    struct Layout {
        std::vector<int> gy0, group_first, x0;
        void add_group(int y, int x) {
            gy0.push_back(y);
            group_first.push_back(int(x0.size()));
            x0.push_back(x);
        }
    };

    // Bands of `rows` rows each (the last one may be shorter), whole rows.
    void cut_rows(int rows) {
        Layout l;
        for (int y = crop_.y0; y < crop_.y1; y += rows) l.add_group(y, crop_.x0);
        l.gy0.push_back(std::max(crop_.y0, crop_.y1));
        l.group_first.push_back(int(l.x0.size()));
        apply(std::move(l));
    }

    // The splats the last cut's bands met in rows [y0, y1), in total and by block of columns; a
    // group of the last cut that reaches beyond those rows adds its share of them by rows.
    void counted_in(int y0, int y1, double& count, std::array<double, kBlocks>& hist) const {
        const int g1 = group_of_row_[size_t(y1 - 1 - crop_.y0)];
        for (int g = group_of_row_[size_t(y0 - crop_.y0)]; g <= g1; ++g) {
            const int ga = gy0_[size_t(g)], gb = gy0_[size_t(g) + 1];
            const double f = double(std::min(y1, gb) - std::max(y0, ga)) / double(gb - ga);
            for (int b = group_first_[size_t(g)]; b < group_first_[size_t(g) + 1]; ++b) {
                count += f * double(merged_[size_t(b)]);
                for (size_t i = 0; i < kBlocks; ++i) hist[i] += f * double(xhist_[size_t(b) * kBlocks + i]);
            }
        }
    }

    // Adds to the last group of `l` the cuts that part its columns into `strips` strips of about
    // equal counts in `hist`, at block edges, none narrower than min_strip_.
    void cut_columns(const std::array<double, kBlocks>& hist, uint64_t strips, Layout& l) const {
        double sum = 0;
        for (double h : hist) sum += h;
        if (!(sum > 0)) return;
        double cum = 0;
        uint64_t j = 1;
        for (int i = 0; i < kBlocks && j < strips; ++i) {
            cum += hist[size_t(i)];
            for (; j < strips && cum * double(strips) >= sum * double(j); ++j) {
                const int x = crop_.x0 + (i + 1) * block_;
                if (x >= l.x0.back() + min_strip_ && x <= crop_.x1 - min_strip_) l.x0.push_back(x);
            }
        }
    }

    void apply(Layout&& l) {
        gy0_ = std::move(l.gy0);
        group_first_ = std::move(l.group_first);
        x0_ = std::move(l.x0);
        group_of_row_.assign(size_t(std::max(0, crop_.height())), 0);
        group_of_band_.assign(x0_.size(), 0);
        for (size_t g = 0; g + 1 < gy0_.size(); ++g) {
            for (int y = gy0_[g]; y < gy0_[g + 1]; ++y) group_of_row_[size_t(y - crop_.y0)] = int(g);
            for (int b = group_first_[g]; b < group_first_[g + 1]; ++b) group_of_band_[size_t(b)] = int(g);
        }
        merged_.assign(bands(), 0);
        xhist_.assign(count_columns_ ? bands() * kBlocks : 0, 0);
    }

    size_t block_of(float x) const {
        return size_t(std::clamp(int(std::floor((x - float(crop_.x0)) / float(block_))), 0, kBlocks - 1));
    }

    // fn(b) for every band the splat's filter footprint reaches, in band order, as
    // for_each_filter_pixel visits its pixels. The groups by table: an integer division per end
    // of every splat, twice per bucket(), was a tenth of bucket()'s time.
    template <class Fn>
    void for_each_band_of(const Splat& sp, Fn&& fn) const {
        const auto [ya, yb] = filter_span(sp.film.y, radius_, crop_.y0, crop_.y1);
        const auto [xa, xb] = filter_span(sp.film.x, radius_, crop_.x0, crop_.x1);
        if (ya > yb || xa > xb) return;  // no pixel of the crop
        const int g1 = group_of_row_[size_t(yb - crop_.y0)];
        for (int g = group_of_row_[size_t(ya - crop_.y0)]; g <= g1; ++g) {
            int b = group_first_[size_t(g)];
            const int e = group_first_[size_t(g) + 1];
            while (b + 1 < e && x0_[size_t(b) + 1] <= xa) ++b;
            for (; b < e && x0_[size_t(b)] <= xb; ++b) fn(b);
        }
    }

    Rect crop_;
    float radius_;
    int rows_;
    int block_;                       // columns per block of xhist_
    int min_strip_;                   // columns: 4 footprints, so that few splats reach two strips
    std::vector<int> gy0_;            // see Layout
    std::vector<int> group_first_;
    std::vector<int> x0_;
    std::vector<int> group_of_row_;   // crop row - crop_.y0 -> its group
    std::vector<int> group_of_band_;  // band -> its group
    std::vector<uint64_t> merged_;    // splats merged per band since the last cut (band b's task writes b)
    std::vector<uint64_t> xhist_;     // bands x kBlocks: each band's splats by block of columns
    bool count_columns_ = false;      // beyond 2 workers: fill xhist_ and cut columns
    ScheduleProbe* probe_ = nullptr;
};

}  // namespace omega
