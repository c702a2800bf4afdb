#pragma once
// Light tracing and BDPT splat across the whole film, so one batch's splats used to be merged
// on the driver thread alone: 10% of a BDPT render on 1 thread, and a serial section that caps
// the speedup on a many-core machine. Here the crop is cut into bands of rows; each splat is
// listed, in merge order, under every band its filter footprint reaches, and the bands are
// merged in parallel. A pixel belongs to one band and receives its splats in the serial order
// (tile order, then the order within a tile), so the sums are bit-identical to the serial merge
// and to any thread count.
//
// Concurrency: merge() and for_each_band() are called on the driver thread, inside nothing; the
// callbacks run on the arena's workers, never two at once for the same pixel.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "film/film.h"
#include "film/filter.h"
#include "integrator/bdpt_tracer.h"

namespace omega {

class SplatBands {
public:
    SplatBands(const Rect& crop, float filter_radius, int band_rows = kBandRows)
        : crop_(crop), radius_(filter_radius), rows_(std::max(1, band_rows)),
          lists_(size_t(std::max(1, (crop.height() + rows_ - 1) / rows_))) {}

    size_t bands() const { return lists_.size(); }
    // Rows [y0, y1) of band b, as a rect of the crop.
    Rect band(size_t b) const {
        Rect r = crop_;
        r.y0 = crop_.y0 + int(b) * rows_;
        r.y1 = std::min(crop_.y1, r.y0 + rows_);
        return r;
    }

    // fn(band_rect) for every band, in parallel.
    template <class Fn>
    void for_each_band(tbb::task_arena& arena, Fn&& fn) const {
        arena.execute([&] {
            tbb::parallel_for(tbb::blocked_range<size_t>(0, bands(), 1), [&](const tbb::blocked_range<size_t>& r) {
                for (size_t b = r.begin(); b != r.end(); ++b) fn(band(b));
            });
        });
    }

    // fn(splat, x, y, filter_weight) for every crop pixel each splat of `tiles` reaches.
    template <class Fn>
    void merge(tbb::task_arena& arena, const Filter& filter, const std::vector<std::vector<Splat>>& tiles, Fn&& fn) {
        for (auto& l : lists_) l.clear();
        for (const auto& list : tiles)
            for (const Splat& sp : list) {
                // The rows for_each_filter_pixel visits, as bands.
                const int ya = std::max(crop_.y0, int(std::floor(sp.film.y - radius_ - 0.5f)));
                const int yb = std::min(crop_.y1 - 1, int(std::ceil(sp.film.y + radius_ - 0.5f)));
                if (ya > yb) continue;
                for (int b = (ya - crop_.y0) / rows_, e = (yb - crop_.y0) / rows_; b <= e; ++b)
                    lists_[size_t(b)].push_back(&sp);
            }
        arena.execute([&] {
            tbb::parallel_for(tbb::blocked_range<size_t>(0, bands(), 1), [&](const tbb::blocked_range<size_t>& r) {
                for (size_t b = r.begin(); b != r.end(); ++b) {
                    const Rect rows = band(b);
                    for (const Splat* sp : lists_[b])
                        for_each_filter_pixel(filter, rows, sp->film, [&](int x, int y, double f) { fn(*sp, x, y, f); });
                }
            });
        });
    }

    static constexpr int kBandRows = 8;

private:
    Rect crop_;
    float radius_;
    int rows_;
    std::vector<std::vector<const Splat*>> lists_;  // per band, in merge order
};

}  // namespace omega
