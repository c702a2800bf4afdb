#include "pathspace/subpath.h"

#include <cmath>

#include "light/light_emission.h"
#include "scene/spawn.h"

namespace omega {

namespace {

// How the first edge of a walk converts its direction density to area at the first hit.
enum class FirstEdge { SolidAngle, Projected };

// Veach's correction for shading normals in adjoint transport: keeps light tracing consistent
// with radiance transport when ns != ng.
float shading_correction(const PathVertex& v, const Vec3& wo, const Vec3& wi) {
    float num = absdot(wo, v.hit.ns) * absdot(wi, v.hit.ng);
    float den = absdot(wo, v.hit.ng) * absdot(wi, v.hit.ns);
    return den > 0 ? num / den : 0.f;
}

bool consistent_side(const Vec3& w_world, const Vec3& ng, float cos_shading) { return dot(w_world, ng) * cos_shading > 0; }

int random_walk(const Scene& scene, Ray ray, Rgb beta, double pdf_dir, FirstEdge first, TransportMode mode,
                const WalkLimits& lim, Rng& rng, TracerStats& stats, std::vector<PathVertex>& path) {
    bool first_edge = true;
    while (int(path.size()) < lim.max_vertices) {
        SurfaceHit hit;
        ++stats.rays;
        PathVertex& prev_ref = path.back();
        if (!scene.intersect(ray, hit)) {
            // A camera subpath that escapes ends on the environment, a vertex at infinity.
            int env = scene.environment_light();
            if (mode == TransportMode::Radiance && env >= 0) {
                PathVertex v;
                v.kind = VertexKind::Light;
                v.infinite = true;
                v.dir = -ray.d;
                v.light = env;
                v.beta = beta;
                v.pdf_fwd = pdf_dir;
                path.push_back(v);
            }
            break;
        }
        PathVertex v;
        v.kind = VertexKind::Surface;
        v.hit = hit;
        v.wo = -normalize(ray.d);
        v.bsdf = &scene.bsdf_of(hit);
        v.light = scene.shapes()[hit.shape].light;
        v.shading = Frame::from_normal(hit.ns);
        v.beta = beta;
        if (first_edge && first == FirstEdge::Projected) v.pdf_fwd = pdf_dir * absdot(v.wo, hit.ng);
        else v.pdf_fwd = to_area_density(prev_ref, pdf_dir, v);
        first_edge = false;
        path.push_back(v);
        if (int(path.size()) >= lim.max_vertices) break;
        PathVertex& cur = path.back();
        if (std::holds_alternative<BlackBsdf>(*cur.bsdf)) break;

        Vec3 wo_local = cur.shading.to_local(cur.wo);
        if (wo_local.z == 0) break;
        float uc = rng.next_1d();
        Vec2 u{rng.next_1d(), rng.next_1d()};
        auto bs = bsdf_sample(*cur.bsdf, wo_local, uc, u, mode);
        if (!bs || is_black(bs->weight)) break;
        Vec3 wi = cur.shading.to_world(bs->wi);
        if (!consistent_side(wi, hit.ng, bs->wi.z)) break;
        double pdf_fwd_sa, pdf_rev_sa;
        if (bs->is_delta()) {
            cur.delta = true;
            pdf_fwd_sa = pdf_rev_sa = 1.0;  // discrete choice: cancels in every ratio
        } else {
            pdf_fwd_sa = bs->pdf_sa;
            pdf_rev_sa = bsdf_pdf_sa(*cur.bsdf, bs->wi, wo_local, mode);
        }
        beta *= bs->weight;
        if (mode == TransportMode::Importance) beta *= shading_correction(cur, cur.wo, wi);
        // The density of the previous vertex as seen from this one, now that both directions are known.
        PathVertex& prev = path[path.size() - 2];
        prev.pdf_rev = cur.delta ? 1.0 : to_area_density(cur, pdf_rev_sa, prev);

        if (int(path.size()) > lim.rr_depth) {
            float q = std::min(1.f, max_component(beta));
            if (q < 1.f) {
                if (!(q > 0) || rng.next_1d() >= q) break;
                beta /= q;
            }
        }
        ray = spawn_ray(hit, wi);
        // After a delta choice the next vertex's density is the discrete 1 (marker -1: no conversion).
        pdf_dir = cur.delta ? -1.0 : pdf_fwd_sa;
    }
    return int(path.size());
}

}  // namespace

double to_area_density(const PathVertex& from, double pdf_sa, const PathVertex& to) {
    if (pdf_sa < 0) return 1.0;  // through a delta event
    if (to.infinite) return pdf_sa;
    Vec3 d = to.p() - from.p();
    double dist2 = double(length_sq(d));
    if (!(dist2 > 0)) return 0.0;
    double pdf = pdf_sa / dist2;
    if (to.is_on_surface()) pdf *= std::abs(double(dot(to.hit.ng, d))) / std::sqrt(dist2);
    return pdf;
}

Rgb vertex_f(const PathVertex& v, const Vec3& wi, TransportMode mode) {
    Vec3 wo_l = v.shading.to_local(v.wo), wi_l = v.shading.to_local(wi);
    if (!consistent_side(wi, v.hit.ng, wi_l.z)) return Rgb(0.f);
    Rgb f = bsdf_eval(*v.bsdf, wo_l, wi_l, mode);
    if (mode == TransportMode::Importance) f *= shading_correction(v, v.wo, wi);
    return f;
}

double vertex_pdf_sa(const PathVertex& v, const Vec3& from, const Vec3& to) {
    return bsdf_pdf_sa(*v.bsdf, v.shading.to_local(from), v.shading.to_local(to), TransportMode::Radiance);
}

int generate_camera_subpath(const Scene& scene, const Ray& ray, const WalkLimits& lim, Rng& rng, TracerStats& stats,
                            std::vector<PathVertex>& path) {
    path.clear();
    if (lim.max_vertices <= 0) return 0;
    const Sensor& sensor = scene.sensor();
    PathVertex cam;
    cam.kind = VertexKind::Sensor;
    cam.hit.p = ray.o;
    Sensor::Pdf pdf = sensor.pdf_we(ray.o, ray.d);
    const bool ortho = sensor.delta_direction();
    // Orthographic: the direction is the delta part; the vertex density is the position's.
    cam.pdf_fwd = ortho ? 1.0 : pdf.pos;
    cam.beta = Rgb(1.f);
    path.push_back(cam);
    if (!(pdf.pos > 0) || !(pdf.dir > 0)) return 1;  // cannot happen for a ray the sensor generated
    return random_walk(scene, ray, Rgb(1.f), ortho ? pdf.pos : pdf.dir, ortho ? FirstEdge::Projected : FirstEdge::SolidAngle,
                       TransportMode::Radiance, lim, rng, stats, path);
}

int generate_light_subpath(const Scene& scene, const WalkLimits& lim, Rng& rng, TracerStats& stats,
                           std::vector<PathVertex>& path) {
    path.clear();
    const auto& sel = scene.light_selection();
    if (sel.empty() || lim.max_vertices <= 0) return 0;
    float u_sel = rng.next_1d();
    Vec2 u_pos{rng.next_1d(), rng.next_1d()}, u_dir{rng.next_1d(), rng.next_1d()};
    size_t li = sel.sample(u_sel);
    double pmf = sel.pmf(li);
    const Light& light = scene.lights()[li];
    auto e = light_sample_le(scene, light, u_pos, u_dir);
    if (!e || is_black(e->Le)) return 0;
    PathVertex lv;
    lv.kind = VertexKind::Light;
    lv.light = int(li);
    lv.hit = e->origin;
    lv.infinite = e->infinite;
    lv.dir = e->ray.d;
    // Spatial density for finite lights; the direction's for lights at infinity.
    lv.pdf_fwd = pmf * (e->infinite ? e->pdf_dir : e->pdf_pos);
    lv.beta = e->Le / float(pmf * (e->infinite ? e->pdf_dir : e->pdf_pos));
    path.push_back(lv);
    double cos0 = std::holds_alternative<AreaLight>(light) ? absdot(e->origin.ng, e->ray.d) : 1.0;
    Rgb beta = e->Le * float(cos0 / (pmf * e->pdf_pos * e->pdf_dir));
    if (!is_finite(beta) || is_black(beta)) return 1;
    if (e->infinite)
        return random_walk(scene, e->ray, beta, e->pdf_pos, FirstEdge::Projected, TransportMode::Importance, lim, rng,
                           stats, path);
    return random_walk(scene, e->ray, beta, e->delta_dir ? -1.0 : e->pdf_dir, FirstEdge::SolidAngle,
                       TransportMode::Importance, lim, rng, stats, path);
}

}  // namespace omega
