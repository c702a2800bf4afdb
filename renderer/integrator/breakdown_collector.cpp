#include "integrator/breakdown_collector.h"

#include <fmt/format.h>

#include <sstream>
#include <stdexcept>

namespace omega {

namespace {

double luminance_d(const Rgb& c) { return 0.2126 * double(c.x) + 0.7152 * double(c.y) + 0.0722 * double(c.z); }

}  // namespace

Rect parse_breakdown_box(const std::string& text) {
    std::vector<int> v;
    std::istringstream in(text);
    for (std::string f; std::getline(in, f, ',');) {
        size_t used = 0;
        int n = 0;
        try {
            n = std::stoi(f, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != f.size())
            throw std::invalid_argument(fmt::format("breakdown box '{}': '{}' is not an integer", text, f));
        v.push_back(n);
    }
    if (v.size() != 4) throw std::invalid_argument(fmt::format("breakdown box '{}': want x0,y0,x1,y1", text));
    return Rect{v[0], v[1], v[2], v[3]};
}

BreakdownCollector::BreakdownCollector(const BreakdownDesc& desc, const Rect& crop, bool splatting)
    : desc_(desc), region_(desc.box.value_or(crop)) {
    if (desc.max_length < 1 || desc.max_length > kMaxBreakdownLength)
        throw std::invalid_argument(fmt::format("breakdown length {}: must be 1 to {}", desc.max_length, kMaxBreakdownLength));
    const Rect& b = region_;
    if (b.x0 >= b.x1 || b.y0 >= b.y1 || b.x0 < crop.x0 || b.y0 < crop.y0 || b.x1 > crop.x1 || b.y1 > crop.y1)
        throw std::invalid_argument(fmt::format(
            "breakdown box {},{},{},{}: must be a non-empty pixel box [x0, x1) x [y0, y1) inside the crop {},{},{},{}", b.x0,
            b.y0, b.x1, b.y1, crop.x0, crop.y0, crop.x1, crop.y1));
    if (splatting) {
        camera_scale_ = double(crop.area()) / double(region_.area());
        splat_scale_ = 1.0 / double(region_.area());
    }
}

std::string BreakdownCollector::region_name() const {
    if (!desc_.box) return "image";
    return fmt::format("box:{}:{}:{}:{}", region_.x0, region_.y0, region_.x1, region_.y1);
}

void BreakdownCollector::add_path_sample(int x, int y, const PathClassTracker& classes) {
    if (!in_region(x, y)) return;
    Local& l = local_.local();
    l.unit.clear();
    for (const auto& [key, v] : classes.contributions()) l.unit.add(key, luminance_d(v));
    l.stats.add_unit(l.unit);
}

void BreakdownCollector::add_splatting_sample(int x, int y, const BdptScratch& scratch, std::span<const Splat> splats,
                                              const Filter& filter) {
    Local& l = local_.local();
    l.unit.clear();
    if (in_region(x, y))
        for (const auto& [key, v] : scratch.class_camera) l.unit.add(key, camera_scale_ * luminance_d(v));
    for (size_t i = 0; i < splats.size(); ++i) {
        double w = 0;  // the splat's filter weight inside the region, as the film spreads it
        for_each_filter_pixel(filter, region_, splats[i].film, [&](int, int, double f) { w += f; });
        if (w > 0) l.unit.add(scratch.splat_classes[i], splat_scale_ * w * luminance_d(splats[i].value));
    }
    l.stats.add_unit(l.unit);
}

BreakdownStats BreakdownCollector::stats() const {
    BreakdownStats all = base_;
    for (const Local& l : local_) all.merge(l.stats);  // exact sums: any order gives the same bits
    return all;
}

BreakdownReport BreakdownCollector::report() const { return make_breakdown_report(stats(), region_name(), desc_.max_length); }

}  // namespace omega
