#include "integrator/path_tracer.h"

#include "integrator/mis.h"
#include "scene/spawn.h"

namespace omega {

namespace {

// A direction counts as leaving on the side the shading frame says only if the geometric normal
// agrees; otherwise interpolated normals would leak light through surfaces.
inline bool consistent_side(const Vec3& w_world, const Vec3& ng, float cos_shading) {
    return dot(w_world, ng) * cos_shading > 0;
}

}  // namespace

Rgb PathTracer::sample_direct(const SurfaceHit& hit, const Frame& shading, const Vec3& wo_local, const Bsdf& bsdf,
                              Sampler& sampler, TracerStats& stats) const {
    const auto& sel = scene_.light_selection();
    if (sel.empty()) return Rgb(0.f);
    float u_sel = sampler.next_1d();
    Vec2 u = sampler.next_2d();
    size_t li = sel.sample(u_sel);
    float pmf = sel.pmf(li);
    const Light& light = scene_.lights()[li];
    auto ls = light_sample_li(scene_, light, hit.p, u);
    if (!ls || ls->pdf_sa <= 0 || is_black(ls->Li)) return Rgb(0.f);
    Vec3 wi_local = shading.to_local(ls->wi);
    if (!consistent_side(ls->wi, hit.ng, wi_local.z)) return Rgb(0.f);
    Rgb f = bsdf_eval(bsdf, wo_local, wi_local, TransportMode::Radiance) * std::abs(wi_local.z);
    if (is_black(f)) return Rgb(0.f);
    Ray shadow = ls->infinite ? spawn_ray(hit, ls->wi) : spawn_ray_to(hit, ls->p, ls->p_error, ls->n);
    ++stats.rays;
    if (scene_.occluded(shadow)) return Rgb(0.f);
    float pdf_light_sa = pmf * ls->pdf_sa;
    float w = ls->delta ? 1.f : power_heuristic(pdf_light_sa, bsdf_pdf_sa(bsdf, wo_local, wi_local, TransportMode::Radiance));
    return f * ls->Li * (w / pdf_light_sa);
}

Rgb PathTracer::radiance(Ray ray, Sampler& sampler, TracerStats& stats, CameraLpeTracker* lpe) const {
    const int max_depth = settings_.max_depth >= 0 ? settings_.max_depth : kMaxUnboundedDepth;
    const bool nee = settings_.light_sampling;
    Rgb L(0.f), beta(1.f);
    bool prev_delta = true;     // the camera vertex has no BSDF density to weigh against
    float prev_pdf_sa = 0;      // solid-angle density of the direction that made the current edge
    Vec3 prev_p = ray.o;
    float eta_scale = 1.f;      // undoes radiance scaling at refraction for Russian roulette
    const auto& sel = scene_.light_selection();

    // k is the number of edges of the path so far, counting the one being traced.
    for (int k = 1;; ++k) {
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
                const Rgb c = beta * le * w;
                L += c;
                if (lpe) lpe->emit(c);
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
                }
                const Rgb c = beta * le * w;
                L += c;
                if (lpe) lpe->emit(c);
            }
        }
        if (k >= max_depth) break;  // the next edge would exceed max_depth

        Bsdf textured;  // holds the BSDF at this hit when its material is textured
        const Bsdf& bsdf = scene_.bsdf_at(hit, textured);
        if (std::holds_alternative<BlackBsdf>(bsdf)) break;
        Frame shading = Frame::from_normal(hit.ns);
        Vec3 wo_local = shading.to_local(wo);
        if (wo_local.z == 0) break;

        // Vertex k of the path (k edges before it) draws from its own block of dimensions.
        if (nee && bsdf_has_nondelta(bsdf)) {
            sampler.start_dimension(dims::camera_walk(k, dims::kDirect));
            const Rgb c = beta * sample_direct(hit, shading, wo_local, bsdf, sampler, stats);
            L += c;
            if (lpe) lpe->emit_via(bsdf, c);
        }

        sampler.start_dimension(dims::camera_walk(k, dims::kScatter));
        float uc = sampler.next_1d();
        Vec2 u = sampler.next_2d();
        auto bs = bsdf_sample(bsdf, wo_local, uc, u, TransportMode::Radiance);
        if (!bs || is_black(bs->weight)) break;
        Vec3 wi = shading.to_world(bs->wi);
        if (!consistent_side(wi, hit.ng, bs->wi.z)) break;
        beta *= bs->weight;
        prev_delta = bs->is_delta();
        if (lpe) lpe->scatter(bsdf, prev_delta);
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
