#pragma once
// The render session's side of the breakdown (integrator/breakdown.h): turns each camera
// sample's contributions by class into one unit on the film's scale, inside the region, and
// sums the units per thread.
//
// Scale: a unit's X has the region's mean pixel luminance as its mean.
//  - Path tracing: every value lands in its own pixel, so the units are the camera samples of
//    the region's pixels, X = luminance of the sample's value.
//  - Light tracing and BDPT: one batch (a sample index) holds one unit per crop pixel, and a
//    pixel's batch value is its camera part plus every light path's splats times f / N_crop
//    (render_session.cpp). So X = (N_crop / n_R) camera part (pixel in the region) +
//    sum over splats of luminance times the filter weight inside the region / n_R.
//
// Concurrency: add_* from the worker threads (each sums into its thread's stats); report()
// from the driver thread while no worker runs.
#include <tbb/enumerable_thread_specific.h>

#include <span>

#include "film/filter.h"
#include "integrator/bdpt_tracer.h"
#include "integrator/breakdown.h"

namespace omega {

class BreakdownCollector {
public:
    // Throws std::invalid_argument when the box is empty or not inside the crop.
    BreakdownCollector(const BreakdownDesc& desc, const Rect& crop, bool splatting);
    int max_length() const { return desc_.max_length; }
    const Rect& region() const { return region_; }

    // Path tracing: camera sample at pixel (x, y) (a finite one), its contributions by class.
    void add_path_sample(int x, int y, const PathClassTracker& classes);
    // Light tracing and BDPT: camera sample at pixel (x, y) with its splats (scratch holds their
    // classes, as the tracer left them).
    void add_splatting_sample(int x, int y, const BdptScratch& scratch, std::span<const Splat> splats,
                              const Filter& filter);

    BreakdownReport report() const;
    // The per-thread sums merged (exactly: any order gives the same bits), with the base.
    BreakdownStats stats() const;
    // Sums of samples rendered before (a resumed job's checkpoint), added to every report.
    // Driver thread, before the render starts.
    void add_base(const BreakdownStats& s) { base_.merge(s); }
    // "image", or "box:x0:y0:x1:y1".
    std::string region_name() const;

private:
    bool in_region(int x, int y) const { return x >= region_.x0 && x < region_.x1 && y >= region_.y0 && y < region_.y1; }
    BreakdownDesc desc_;
    Rect region_;
    double camera_scale_ = 1, splat_scale_ = 1;
    struct Local {
        BreakdownStats stats;
        BreakdownUnit unit;
    };
    tbb::enumerable_thread_specific<Local> local_;
    BreakdownStats base_;
};

// "x0,y0,x1,y1" to a box; throws std::invalid_argument naming what is wrong.
Rect parse_breakdown_box(const std::string& text);

}  // namespace omega
