#include "integrator/path_tracer.h"

#include "integrator/mis.h"
#include "pathspace/mirror_connector.h"
#include "scene/spawn.h"

namespace omega {

PathTracer::PathTracer(const Scene& scene, const PathTracerSettings& settings) : scene_(scene), settings_(settings) {
    if (settings_.light_sampling && settings_.mirror_connector) {
        auto m = std::make_shared<PlanarMirrors>(find_planar_mirrors(scene));
        if (!m->empty()) mirrors_ = std::move(m);
    }
}

// Inlined into radiance(): returned through memory, its 24 bytes were written as three stores and
// read back as one 16-byte load, which the store buffer cannot forward (a stall per vertex).
[[gnu::always_inline]] inline PathTracer::DirectDraw PathTracer::draw_direct(const SurfaceHit& hit, Sampler& sampler,
                                                                              const Vec2* ahead) const {
    const auto& sel = scene_.light_selection();
    if (sel.empty()) return {};
    float u_sel = sampler.next_1d_if(sel.size() > 1);  // one light: nothing to choose
    size_t li = sel.sample(u_sel);
    const Light& light = scene_.lights()[li];
    if (light_faces_away(scene_, light, hit.p)) {  // no sample of it could contribute
        sampler.skip_2d();
        return {};
    }
    return {&light, sel.pmf(li), sampler.next_2d(ahead)};
}

Rgb PathTracer::eval_direct(const DirectDraw& d, const SurfaceHit& hit, const Frame& shading, const Vec3& wo_local,
                            const Bsdf& bsdf, TracerStats& stats) const {
    if (!d.light) return Rgb(0.f);
    auto ls = light_sample_li(scene_, *d.light, hit.p, d.u);
    if (!ls || ls->pdf_sa <= 0 || is_black(ls->Li)) return Rgb(0.f);
    Vec3 wi_local = shading.to_local(ls->wi);
    if (!consistent_side(ls->wi, hit.ng, wi_local.z)) return Rgb(0.f);
    Rgb f = bsdf_eval(bsdf, wo_local, wi_local, TransportMode::Radiance) * std::abs(wi_local.z);
    if (is_black(f)) return Rgb(0.f);
    Ray shadow = ls->infinite ? spawn_ray(hit, ls->wi) : spawn_ray_to(hit, ls->p, ls->p_error, ls->n);
    ++stats.rays;
    if (scene_.occluded(shadow)) return Rgb(0.f);
    float pdf_light_sa = d.pmf * ls->pdf_sa;
    float w = ls->delta ? 1.f : power_heuristic(pdf_light_sa, bsdf_pdf_sa(bsdf, wo_local, wi_local, TransportMode::Radiance));
    return f * ls->Li * (w / pdf_light_sa);
}

Rgb PathTracer::sample_direct_via_mirrors(const SurfaceHit& hit, const Frame& shading, const Vec3& wo_local,
                                          const Bsdf& bsdf, int k, Sampler& sampler, TracerStats& stats) const {
    Rgb L(0.f);
    for (size_t i = 0; i < mirrors_->list.size(); ++i) {
        sampler.start_dimension(dims::mirror_light(k, int(i)));
        auto ms = sample_light_chain(scene_, mirrors_->list[i], hit, shading, wo_local, bsdf, sampler, stats);
        if (!ms) continue;
        const float w = ms->delta_light ? 1.f : power_heuristic(ms->pdf_light_sa, ms->pdf_bsdf_sa);
        L += ms->L * w;
    }
    return L;
}

Rgb PathTracer::radiance(Ray ray, Sampler& sampler, TracerStats& stats, CameraLpeTracker* lpe,
                         PathClassTracker* classes) const {
    const int max_depth = settings_.max_depth >= 0 ? settings_.max_depth : kMaxUnboundedDepth;
    const bool nee = settings_.light_sampling;
    Rgb L(0.f), beta(1.f);
    bool prev_delta = true;     // the camera vertex has no BSDF density to weigh against
    float prev_pdf_sa = 0;      // solid-angle density of the direction that made the current edge
    Vec3 prev_p = ray.o;
    float eta_scale = 1.f;      // undoes radiance scaling at refraction for Russian roulette
    const auto& sel = scene_.light_selection();
    // The planar-mirror connector's other strategy: BSDF sampling from a vertex x that ran the
    // connector, one delta reflection off mirror `via_mirror`, then a light. Such a chain is
    // weighed against the connector's density (power heuristic in solid angle at x), as plain
    // NEE is weighed against BSDF sampling; any other chain through a delta vertex keeps weight 1.
    int via_mirror = -1;
    Vec3 via_x;
    float via_pdf_sa = 0;
    bool origin_prev = false;  // the vertex that spawned the current edge ran the connector
    Vec3 origin_p;
    float origin_pdf_sa = 0;

    bool direct_pays = true;   // the last vertex used its light sample's 2D draw (see below)

    // k is the number of edges of the path so far, counting the one being traced.
    for (int k = 1;; ++k) {
        // This vertex's 2D draws, computed before the ray is traced where the sampler allows
        // (sobol): they need nothing from the hit, and their hash chains then no longer lie on
        // the dependent chain from the hit to the next ray.
        // Not for a vertex that ends the path (k = max_depth) and, for the light sample, not where
        // the last vertex culled its own (light_faces_away): in a room lit from one side that is
        // most vertices, and a draw computed for nothing is a hash chain's worth of work wasted.
        // Either way the value is the same, so the image is too.
        const bool ahead = sampler.order_free() && k < max_depth && k < dims::kMaxDepth;
        const bool direct_ahead = ahead && nee && direct_pays;
        Vec2 u_direct_ahead, u_scatter_ahead;
        if (direct_ahead) u_direct_ahead = sampler.sobol_2d_at(dims::camera_walk(k, dims::kDirect + 1));
        if (ahead) u_scatter_ahead = sampler.sobol_2d_at(dims::camera_walk(k, dims::kScatter + 1));
        SurfaceHit hit;
        ++stats.rays;
        if (!scene_.intersect(ray, hit)) {
            int env = scene_.environment_light();
            if (env >= 0) {
                const Light& el = scene_.lights()[size_t(env)];
                const Vec3 d = normalize(ray.d);
                Rgb le = environment_le(el, d);
                float w = prev_delta || !nee ? 1.f
                                             : power_heuristic(prev_pdf_sa, sel.pmf(size_t(env)) * environment_pdf_li_sa(el, d));
                if (via_mirror >= 0)
                    w = power_heuristic(via_pdf_sa, mirror_environment_pdf_sa(scene_, mirrors_->list[size_t(via_mirror)],
                                                                             via_x, size_t(env), d));
                const Rgb c = beta * le * w;
                L += c;
                if (lpe) lpe->emit(c);
                if (classes) classes->emit(k, c);
            }
            break;
        }
        const Shape& shape = scene_.shapes()[hit.shape];
        Vec3 wo = -ray.d / length(ray.d);
        if (shape.light >= 0) {
            const auto& al = std::get<AreaLight>(scene_.lights()[size_t(shape.light)]);
            Rgb le = area_light_le(al, hit, wo);
            if (!is_black(le)) {
                float w = 1.f;
                if (!prev_delta && nee) {
                    float pdf_light_sa = sel.pmf(size_t(shape.light)) * light_pdf_li_sa(scene_, al, prev_p, hit);
                    w = power_heuristic(prev_pdf_sa, pdf_light_sa);
                } else if (via_mirror >= 0) {
                    w = power_heuristic(via_pdf_sa, mirror_light_pdf_sa(scene_, mirrors_->list[size_t(via_mirror)], via_x,
                                                                        size_t(shape.light), hit));
                }
                const Rgb c = beta * le * w;
                L += c;
                if (lpe) lpe->emit(c);
                if (classes) classes->emit(k, c);
            }
        }
        if (k >= max_depth) break;  // the next edge would exceed max_depth

        Bsdf textured;  // holds the BSDF at this hit when its material is textured
        const Bsdf& bsdf = scene_.bsdf_at(hit, textured);
        if (std::holds_alternative<BlackBsdf>(bsdf)) break;
        Frame shading = Frame::from_normal(hit.ns);
        Vec3 wo_local = shading.to_local(wo);
        if (wo_local.z == 0) break;

        // Vertex k of the path (k edges before it) draws from its own block of dimensions, in the
        // order next-event estimation, connector, scatter (the independent sampler's stream).
        // The BSDF sample is taken before the light is evaluated: the next ray depends on it and
        // not on the shadow ray, so its dependent chain (hashes, warp, frame) runs while the
        // light sample and the shadow ray are in flight, rather than after them.
        const bool nondelta = bsdf_has_nondelta(bsdf);
        DirectDraw direct;
        if (nee && nondelta) {
            sampler.start_dimension(dims::camera_walk(k, dims::kDirect));
            direct = draw_direct(hit, sampler, direct_ahead ? &u_direct_ahead : nullptr);
            direct_pays = direct.light != nullptr;
        }
        // The connector's chain has two more edges: x -> mirror -> light.
        const bool connector = mirrors_ && nondelta && k + 2 <= max_depth;
        Rgb c_connector(0.f);
        if (connector) c_connector = beta * sample_direct_via_mirrors(hit, shading, wo_local, bsdf, k, sampler, stats);

        sampler.start_dimension(dims::camera_walk(k, dims::kScatter));
        float uc = sampler.next_1d_if(bsdf_sample_uses_uc(bsdf));
        const Vec2 u = sampler.next_2d(ahead ? &u_scatter_ahead : nullptr);
        auto bs = bsdf_sample(bsdf, wo_local, uc, u, TransportMode::Radiance);

        if (nee && nondelta) {
            const Rgb c = beta * eval_direct(direct, hit, shading, wo_local, bsdf, stats);
            L += c;
            if (lpe) lpe->emit_via(bsdf, c);
            if (classes) classes->emit_via(k, c);
        }
        if (connector) {
            L += c_connector;
            if (lpe) lpe->emit_via_mirror(bsdf, c_connector);  // x, then the mirror (S), then L
            if (classes) classes->emit_via_mirror(k, c_connector);
        }

        if (!bs || is_black(bs->weight)) break;
        Vec3 wi = shading.to_world(bs->wi);
        if (!consistent_side(wi, hit.ng, bs->wi.z)) break;
        beta *= bs->weight;
        // A delta reflection off a connector mirror right after a connector vertex: the next
        // light hit is a chain the connector could have sampled (see via_mirror above).
        const int mi = mirrors_ ? mirrors_->index(hit.shape) : -1;
        if (bs->is_delta() && mi >= 0 && origin_prev) {
            via_mirror = mi;
            via_x = origin_p;
            via_pdf_sa = origin_pdf_sa;
        } else {
            via_mirror = -1;
        }
        origin_prev = connector && !bs->is_delta();
        origin_p = hit.p;
        origin_pdf_sa = bs->pdf_sa;
        prev_delta = bs->is_delta();
        if (lpe) lpe->scatter(bsdf, prev_delta);
        if (classes) classes->scatter(k, prev_delta);
        prev_pdf_sa = bs->pdf_sa;
        prev_p = hit.p;
        if (bs->lobe & kLobeTransmission) eta_scale *= sqr(bs->eta);

        if (k >= settings_.rr_depth) {
            // Survive with probability equal to the throughput (without the eta^2 radiance
            // scaling), so the weight after survival stays at 1. Capping survival below 1 (as
            // pbrt-v3 did) gives infinite variance in high-albedo scenes: E[beta^2] grows as
            // (rho^2/q)^k.
            float q = std::min(1.f, max_component(beta) * eta_scale);
            if (q < 1.f) {
                sampler.start_dimension(dims::camera_walk(k, dims::kRoulette));
                if (!(q > 0) || sampler.next_1d() >= q) break;
                beta /= q;
            }
        }
        ray = spawn_ray(hit, wi);
    }
    return L;
}

}  // namespace omega
