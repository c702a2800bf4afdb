#include "pathspace/subpath.h"

#include <cmath>
#include <span>

#include "light/light_emission.h"
#include "math/float_bits.h"
#include "scene/spawn.h"

namespace omega {

namespace {

// Veach's correction for shading normals in adjoint transport: keeps light tracing consistent
// with radiance transport when ns != ng.
float shading_correction(const PathVertex& v, const Vec3& wo, const Vec3& wi) {
    const float den = absdot(wo, v.hit.ng) * absdot(wi, v.hit.ns);
    // Without shading normals (ns is ng, bit for bit) num is den, the same products in the same
    // order, so the ratio is exactly 1: skip the division (BDPT evaluates this per connection).
    if (v.hit.ns == v.hit.ng) return den > 0 ? 1.f : 0.f;
    const float num = absdot(wo, v.hit.ns) * absdot(wi, v.hit.ng);
    return den > 0 ? num / den : 0.f;
}


// Density with which the walk's last vertex, arriving from v, generates its predecessor.
double density_back(const Scene&, std::span<const PathVertex> path, const PathVertex& v) {
    const PathVertex& cur = path.back();
    const PathVertex& pred = path[path.size() - 2];
    if (cur.kind != VertexKind::Surface) return 0.0;
    if (cur.delta) return 1.0;
    return to_area_density(cur, vertex_pdf_sa(cur, direction(cur, v), direction(cur, pred)), pred);
}

// Density with which the walk's last vertex generates v (area at v; solid angle at infinity).
double density_towards(const Scene& scene, std::span<const PathVertex> path, const PathVertex& v) {
    const PathVertex& cur = path.back();
    if (cur.kind == VertexKind::Sensor) return sensor_density_at(scene, cur, v);
    if (cur.kind == VertexKind::Light) return emission_density_at(scene, cur, v);
    if (cur.delta) return 1.0;
    return to_area_density(cur, vertex_pdf_sa(cur, cur.wo, direction(cur, v)), v);
}

// Both densities a new vertex v settles (forward at v, reverse at the predecessor of the walk's
// last vertex) as density_towards and density_back give them; a non-delta surface scatters both
// between the same two directions, which go to its shading frame once. `path` holds the vertices
// before v (v itself may already be stored after them).
void walk_densities(const Scene& scene, std::span<PathVertex> path, PathVertex& v) {
    const size_t n = path.size();
    const PathVertex& cur = path.back();
    if (cur.kind == VertexKind::Surface && !cur.delta) {
        // cur.wo is direction(cur, predecessor), computed from the same positions.
        const Vec3 wo_l = cur.shading.to_local(cur.wo), w_l = cur.shading.to_local(direction(cur, v));
        v.pdf_fwd = to_area_density(cur, bsdf_pdf_sa(*cur.bsdf, wo_l, w_l, TransportMode::Radiance), v);
        if (n >= 2) path[n - 2].pdf_rev = to_area_density(cur, bsdf_pdf_sa(*cur.bsdf, w_l, wo_l, TransportMode::Radiance), path[n - 2]);
        return;
    }
    v.pdf_fwd = density_towards(scene, path, v);
    if (n >= 2) path[n - 2].pdf_rev = density_back(scene, path, v);
}

// spawn_ray moved the origin off the surface by its error bound: about 4e-7 of the coordinates,
// so 0.04 units at 1e5 from the origin. The walk's next vertex must lie on the ray from the vertex
// itself, or every emitted ray lands as if the light were that much closer (light tracing read
// +3% under a unit-sized light at 1e5). Exact for a planar receiver; curved ones keep Embree's
// point, and so do grazing hits, where the shift along the surface would be unbounded.
void reanchor_hit(const Vec3& from, const Ray& ray, SurfaceHit& hit) {
    const Vec3d off = Vec3d(ray.o) - Vec3d(from);
    if (off == Vec3d(0.0) || !hit.planar) return;
    const Vec3d d(ray.d), m(hit.ng);
    const double md = dot(m, d);
    if (!(std::abs(md) > 1e-2 * length(d))) return;
    const Vec3d corr = off - d * (dot(m, off) / md);
    if (!(length(corr) < 4 * length(off))) return;
    const Vec3 p = Vec3(Vec3d(hit.p) - corr);
    hit.p_error += abs(p) * gamma_bound(2) + abs(Vec3(corr)) * gamma_bound(2);
    hit.p = p;
}

// A light subpath edge `ray` (up to tmax) that crosses the lens: record the t = 0 path.
void record_lens_crossing(const Scene& scene, const Ray& ray, float tmax, const Rgb& beta,
                          const std::vector<PathVertex>& path, std::vector<LensCrossing>& out) {
    auto h = scene.sensor().intersect_lens(ray, tmax);
    if (!h) return;
    LensCrossing c;
    c.s = int(path.size());
    c.lens = sensor_vertex(scene, h->p);
    c.lens.pdf_fwd = density_towards(scene, path, c.lens);
    c.beta = beta;
    c.film = h->film;
    c.importance = h->importance;
    if (c.lens.pdf_fwd > 0 && !is_black(beta)) out.push_back(c);
}

int random_walk(const Scene& scene, Ray ray, Rgb beta, TransportMode mode, const WalkLimits& lim, Sampler& sampler,
                TracerStats& stats, std::vector<PathVertex>& path, std::vector<LensCrossing>* lens = nullptr) {
    while (int(path.size()) < lim.max_vertices) {
        // The next vertex's scatter direction draw, computed before the ray is traced where the
        // sampler allows (sobol): it needs nothing from the hit, and its hash chain then no
        // longer lies on the dependent chain from the hit to the next ray.
        const uint32_t scatter_next = mode == TransportMode::Radiance ? dims::camera_walk(int(path.size()), dims::kScatter)
                                                                      : dims::light_walk(int(path.size()), dims::kScatter);
        // Not for the walk's last vertex, which does not scatter.
        const bool ahead = sampler.order_free() && scatter_next != dims::kBeyond && int(path.size()) + 1 < lim.max_vertices;
        Vec2 u_ahead;
        if (ahead) u_ahead = sampler.sobol_2d_at(scatter_next + 1);  // after the lobe's 1D
        SurfaceHit hit;
        ++stats.rays;
        const bool found = scene.intersect(ray, hit);
        if (found && !path.back().infinite) reanchor_hit(path.back().p(), ray, hit);
        if (lens) record_lens_crossing(scene, ray, found ? hit.t : ray.tmax, beta, path, *lens);
        if (!found) {
            // A camera subpath that escapes ends on the environment, a vertex at infinity.
            int env = scene.environment_light();
            if (mode == TransportMode::Radiance && env >= 0) {
                PathVertex v;
                v.kind = VertexKind::Light;
                v.infinite = true;
                v.dir = -normalize(ray.d);
                v.light = env;
                v.beta = beta;
                if (lim.densities) walk_densities(scene, path, v);
                path.push_back(v);
            }
            break;
        }
        // Built in place: a local vertex copied in was read back with wide loads over its narrow
        // stores, which the store buffer cannot forward.
        const size_t n_before = path.size();
        PathVertex& v = path.emplace_back();
        const std::span<PathVertex> before(path.data(), n_before);
        v.kind = VertexKind::Surface;
        v.hit = hit;
        // From the stored positions rather than the ray, so later evaluations at this vertex
        // (connections, reverse densities) agree exactly with what any split recomputes.
        v.wo = before.back().infinite ? -before.back().dir : normalize(before.back().p() - hit.p);
        v.bsdf = &scene.bsdf_of(hit);
        v.light = scene.shapes()[hit.shape].light;
        v.shading = Frame::from_normal(hit.ns);
        v.beta = beta;
        // Densities from the vertex positions, exactly as a connection would compute them, so
        // every split of a path sees the same numbers.
        if (lim.densities) walk_densities(scene, before, v);
        if (int(path.size()) >= lim.max_vertices) break;
        PathVertex& cur = path.back();
        if (std::holds_alternative<BlackBsdf>(*cur.bsdf)) break;

        Vec3 wo_local = cur.shading.to_local(cur.wo);
        if (wo_local.z == 0) break;
        // Vertex j = path.size() - 1 scatters with its block of dimensions (camera or light walk).
        const int j = int(path.size()) - 1;
        auto block = [&](uint32_t slot) {
            return mode == TransportMode::Radiance ? dims::camera_walk(j, slot) : dims::light_walk(j, slot);
        };
        sampler.start_dimension(block(dims::kScatter));
        float uc = sampler.next_1d_if(bsdf_sample_uses_uc(*cur.bsdf));
        const Vec2 u = sampler.next_2d(ahead ? &u_ahead : nullptr);
        Bsdf textured;  // v.bsdf is the scene's material; textures are looked up at the hit's uv
        auto bs = bsdf_sample(resolve_bsdf(*cur.bsdf, cur.hit.uv, textured), wo_local, uc, u, mode);
        if (!bs || is_black(bs->weight)) break;
        Vec3 wi = cur.shading.to_world(bs->wi);
        if (!consistent_side(wi, hit.ng, bs->wi.z)) break;
        cur.delta = bs->is_delta();
        beta *= bs->weight;
        if (mode == TransportMode::Importance) beta *= shading_correction(cur, cur.wo, wi);

        if (int(path.size()) > lim.rr_depth) {
            float q = std::min(1.f, max_component(beta));
            if (q < 1.f) {
                sampler.start_dimension(block(dims::kRoulette));
                if (!(q > 0) || sampler.next_1d() >= q) break;
                beta /= q;
            }
        }
        ray = spawn_ray(hit, wi);
    }
    return int(path.size());
}

}  // namespace

Vec3 direction(const PathVertex& a, const PathVertex& b) {
    if (b.infinite) return -b.dir;
    if (a.infinite) return a.dir;
    return normalize(b.p() - a.p());
}

double sensor_density_at(const Scene& scene, const PathVertex& cam, const PathVertex& next) {
    const Sensor& sensor = scene.sensor();
    if (sensor.delta_direction()) {
        // Orthographic: the direction is the sensor's axis, the position density projects onto
        // the surface. Use the axis itself, not the difference of the rounded vertex positions:
        // far from the origin (1e5) that difference is off by a few 1e-3 rad, pdf_we's direction
        // test rejected it, and the zero density broke the MIS weights (BDPT lost 30%).
        Vec3 axis = Vec3(normalize(sensor.to_world.fwd.vector(Vec3d(0, 0, 1))));
        Sensor::Pdf pdf = sensor.pdf_we(cam.p(), axis);
        return pdf.pos * (next.is_on_surface() ? absdot(axis, next.hit.ng) : 1.f);
    }
    Vec3 w = direction(cam, next);
    Sensor::Pdf pdf = sensor.pdf_we(cam.p(), w);
    return to_area_density(cam, pdf.dir, next);
}

double emission_density_at(const Scene& scene, const PathVertex& v0, const PathVertex& next) {
    const Light& l = scene.lights()[size_t(v0.light)];
    double pdf_pos, pdf_dir;
    if (v0.infinite) {
        // The ray starts on a disk facing the direction: its area density projects onto next.
        light_pdf_le(scene, l, v0.hit.ng, v0.dir, pdf_pos, pdf_dir);
        return pdf_pos * (next.is_on_surface() ? absdot(v0.dir, next.hit.ng) : 1.f);
    }
    light_pdf_le(scene, l, v0.hit.ng, direction(v0, next), pdf_pos, pdf_dir);
    return to_area_density(v0, pdf_dir, next);
}

double to_area_density(const PathVertex& from, double pdf_sa, const PathVertex& to) {
    if (to.infinite) return pdf_sa;
    // In double: float positions subtract exactly, so every split of a path computes the same
    // density even for vertices a few ulps apart (in corners).
    Vec3d d = Vec3d(to.p()) - Vec3d(from.p());
    double dist2 = length_sq(d);
    if (!(dist2 > 0)) return 0.0;
    double pdf = pdf_sa / dist2;
    if (to.is_on_surface()) pdf *= std::abs(dot(Vec3d(to.hit.ng), d)) / std::sqrt(dist2);
    return pdf;
}

Rgb vertex_f(const PathVertex& v, const Vec3& wi, TransportMode mode) {
    return vertex_f(v, wi, VertexLocal{v.shading.to_local(v.wo), v.shading.to_local(wi)}, mode);
}

Rgb vertex_f(const PathVertex& v, const Vec3& wi, const VertexLocal& l, TransportMode mode) {
    const Vec3& wo_l = l.wo;
    const Vec3& wi_l = l.w;
    if (!consistent_side(wi, v.hit.ng, wi_l.z)) return Rgb(0.f);
    Bsdf textured;
    Rgb f = bsdf_eval(resolve_bsdf(*v.bsdf, v.hit.uv, textured), wo_l, wi_l, mode);
    if (mode == TransportMode::Importance) f *= shading_correction(v, v.wo, wi);
    return f;
}

double vertex_pdf_sa(const PathVertex& v, const Vec3& from, const Vec3& to) {
    // No resolve_bsdf: only a diffuse reflectance (of diffuse or plastic) can be textured, and no
    // density depends on it (plastic's lobe selection ignores it on purpose).
    return bsdf_pdf_sa(*v.bsdf, v.shading.to_local(from), v.shading.to_local(to), TransportMode::Radiance);
}

int generate_camera_subpath(const Scene& scene, const Ray& ray, const WalkLimits& lim, Sampler& sampler, TracerStats& stats,
                            std::vector<PathVertex>& path) {
    path.clear();
    if (lim.max_vertices <= 0) return 0;
    const Sensor& sensor = scene.sensor();
    PathVertex cam = sensor_vertex(scene, ray.o);
    Sensor::Pdf pdf = sensor.pdf_we(ray.o, ray.d);
    const bool ortho = sensor.delta_direction();
    // Orthographic: the direction is the delta part; the vertex density is the position's.
    cam.pdf_fwd = ortho ? 1.0 : pdf.pos;
    cam.beta = Rgb(1.f);
    path.push_back(cam);
    if (!(pdf.pos > 0) || !(pdf.dir > 0)) return 1;  // cannot happen for a ray the sensor generated
    return random_walk(scene, ray, Rgb(1.f), TransportMode::Radiance, lim, sampler, stats, path);
}

PathVertex sensor_vertex(const Scene& scene, const Vec3& p) {
    PathVertex v;
    v.kind = VertexKind::Sensor;
    v.hit.p = p;
    if (scene.sensor().lens_hittable()) v.hit.ng = v.hit.ns = scene.sensor().lens_normal();
    return v;
}

int generate_light_subpath(const Scene& scene, const WalkLimits& lim, Sampler& sampler, TracerStats& stats,
                           std::vector<PathVertex>& path, std::vector<LensCrossing>* lens) {
    path.clear();
    if (lens) {
        lens->clear();
        if (!scene.sensor().lens_hittable()) lens = nullptr;
    }
    const auto& sel = scene.light_selection();
    if (sel.empty() || lim.max_vertices <= 0) return 0;
    sampler.start_dimension(dims::kEmit);
    float u_sel = sampler.next_1d_if(sel.size() > 1);
    Vec2 u_pos = sampler.next_2d();
    Vec2 u_dir = sampler.next_2d();
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
    return random_walk(scene, e->ray, beta, TransportMode::Importance, lim, sampler, stats, path, lens);
}

}  // namespace omega
