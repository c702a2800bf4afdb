#include "integrator/bdpt_tracer.h"

#include <bit>

#include "pathspace/mirror_connector.h"

namespace omega {

BdptTracer::BdptTracer(const Scene& scene, const IntegratorDesc& desc)
    : scene_(scene), set_{desc.type}, plan_(plan_strategies(scene)), max_depth_(desc.max_depth) {
    const int md = desc.max_depth < 0 ? kMaxUnboundedDepth : desc.max_depth;
    // k = s + t - 1 <= max_depth: t <= max_depth + 1 (s = 0), s <= max_depth (t = 1).
    camera_limits_ = {desc.type == IntegratorType::Light ? 0 : md + 1, desc.rr_depth + 1};
    // Without a D surface the light subpath is only needed for its endpoint (s = 1, t = 1).
    light_limits_ = {desc.type == IntegratorType::Path ? 0 : (plan_.light_subpaths ? md : 1), desc.rr_depth};
    // t = 0 (s = k light vertices, then the lens): the walk's last vertex must still scatter
    // towards the lens, so it goes one vertex further; longer connections are skipped by k.
    use_t0_ = plan_.t0 && set_.allows(2, 0);
    if (use_t0_ && md < kMaxUnboundedDepth) light_limits_.max_vertices = md + 1;
    // The planar-mirror connector (pathspace/mirror_connector.h): a strategy of its own in the
    // MIS routine, for every (s, t) that StrategySet::allows_connector says (all of them in
    // bdpt, t = 1 in the light tracer, s = 1 in the general path engine).
    if (desc.mirror_connector) {
        auto m = std::make_shared<PlanarMirrors>(find_planar_mirrors(scene));
        if (!m->empty()) {
            mirrors_ = std::move(m);
            set_.mirrors = mirrors_.get();
            set_.lens_hittable = scene.sensor().lens_hittable();
        }
    }
    light_limits_.densities = !set_.single_strategy();
}

Rgb BdptTracer::sample(const Ray& ray, Sampler& sampler, TracerStats& stats, BdptScratch& scratch, std::vector<Splat>& splats,
                       std::vector<StrategyContribution>* per_strategy) const {
    auto& cam = scratch.camera;
    auto& lit = scratch.light;
    const int n_cam = camera_limits_.max_vertices > 0 ? generate_camera_subpath(scene_, ray, camera_limits_, sampler, stats, cam) : 0;
    const int n_light = light_limits_.max_vertices > 0
                            ? generate_light_subpath(scene_, light_limits_, sampler, stats, lit, use_t0_ ? &scratch.lens : nullptr)
                            : 0;
    if (n_light == 0) lit.clear();
    // Without the connector, bdpt's weights come from the subpaths' sums (pathspace/mis_prefix.h).
    const bool prefixed = set_.type == IntegratorType::Bdpt && !set_.mirrors;
    if (prefixed) scratch.connect.prefix.prepare(scene_, lit, cam);

    Rgb L(0.f);
    if (aovs_) {
        for (size_t a = 0; a < aovs_->size(); ++a) scratch.aov_camera[a] = Rgb(0.f);
        scratch.lpe.prepare(*aovs_, lit, n_light, cam, n_cam);
    }
    if (breakdown_length_ > 0) {
        scratch.class_camera.clear();
        scratch.splat_classes.clear();
        // Longer paths are one class: vertices past the breakdown's length never matter.
        auto delta_bits = [&](const std::vector<PathVertex>& v, int n) {
            uint64_t bits = 0;
            for (int i = 1; i < std::min(n, kMaxBreakdownLength + 2); ++i)
                if (v[size_t(i)].delta) bits |= uint64_t(1) << (i - 1);
            return bits;
        };
        scratch.light_delta = delta_bits(lit, n_light);
        scratch.camera_delta = delta_bits(cam, n_cam);
    }
    if (use_t0_) {
        for (const LensCrossing& lc : scratch.lens) {
            if (max_depth_ >= 0 && lc.s > max_depth_) continue;  // k = s edges
            auto c = connect_lens(scene_, lit, lc, set_, scratch.connect);
            if (!c) continue;
            Rgb unweighted = c->L * float(c->importance);
            Rgb weighted = unweighted * float(c->weight);
            if (per_strategy) per_strategy->push_back({lc.s + 1, 0, unweighted, weighted, true, c->film});
            const uint32_t mask = aovs_ ? scratch.lpe.match_lens(lc.s) : 0;
            splats.push_back({c->film, weighted, mask});
            if (breakdown_length_ > 0) record_class(scratch, lc.s, 0, false, true, weighted);
        }
    }
    // One strategy's contribution (s, t; through a mirror or not): the full path as it built it,
    // connection included, is matched and keyed before its MIS-weighted value goes anywhere.
    auto add = [&](const Connection& c, int s, int t, bool via_mirror) {
        const Rgb unweighted = c.splat ? c.L * float(c.importance) : c.L;
        const Rgb weighted = unweighted * float(c.weight);
        if (per_strategy && !via_mirror) per_strategy->push_back({s, t, unweighted, weighted, c.splat, c.film});
        const uint32_t mask = aovs_ ? scratch.lpe.match(s, t, via_mirror) : 0;
        if (breakdown_length_ > 0) record_class(scratch, s, t, via_mirror, c.splat, weighted);
        if (c.splat) {
            splats.push_back({c.film, weighted, mask});
        } else {
            L += weighted;
            for (uint32_t m = mask; m; m &= m - 1) scratch.aov_camera[size_t(std::countr_zero(m))] += weighted;
        }
    };
    // t = 1 needs no camera subpath; s = 1 samples its light vertex afresh (next-event estimation).
    const int t_max = std::max(n_cam, 1);
    for (int t = 1; t <= t_max; ++t) {
        const int s_max = std::max(n_light, 1);
        for (int s = 0; s <= s_max; ++s) {
            const int k = s + t - 1;
            if (k < 1 || (max_depth_ >= 0 && k > max_depth_)) continue;
            if (!set_.allows(s, t)) continue;
            // Skip only what has zero probability (the MIS routine must agree): without a D
            // surface no edge can be connected, except a light endpoint joined to the sensor.
            if ((s == 0 && !plan_.s0) || (s >= 1 && !plan_.connections && !(s == 1 && t == 1))) continue;
            if (t >= 2 && t > n_cam) continue;
            if (s >= 2 && s > n_light) continue;
            if (t == 1 && s > n_light) continue;
            if (s == 0 && cam[size_t(t - 1)].light < 0) continue;  // only a hit light can end here
            if (auto c = connect(scene_, lit, cam, s, t, set_, sampler, stats, scratch.connect)) add(*c, s, t, false);
        }
    }
    // Connections through a planar mirror: the mirror vertex adds an edge, k = s + t.
    if (mirrors_) {
        const int t_top = std::max(n_cam, 1);
        for (int t = 1; t <= t_top; ++t)
            for (int s = 1; s <= std::max(n_light, 1); ++s) {
                if (max_depth_ >= 0 && s + t > max_depth_) continue;
                if (!set_.allows_connector(s, t)) continue;
                if ((t >= 2 && t > n_cam) || ((s >= 2 || t == 1) && s > n_light)) continue;
                for (size_t i = 0; i < mirrors_->list.size(); ++i) {
                    auto c = connect_via_mirror(scene_, int(i), lit, cam, s, t, set_, sampler, stats, scratch.connect);
                    if (c) add(*c, s, t, true);
                }
            }
    }
    scratch.connect.prefix.reset();
    return L;
}

void BdptTracer::record_class(BdptScratch& scratch, int s, int t, bool via_mirror, bool splat, const Rgb& weighted) const {
    const PathClassKey key = t == 0 ? lens_class_key(scratch.light_delta, s, breakdown_length_)
                                    : strategy_class_key(scratch.light_delta, scratch.camera_delta, s, t, via_mirror,
                                                         breakdown_length_);
    if (splat) scratch.splat_classes.push_back(key);
    else if (!is_black(weighted)) scratch.class_camera.emplace_back(key, weighted);
}

}  // namespace omega
