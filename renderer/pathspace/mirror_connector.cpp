#include "pathspace/mirror_connector.h"

#include <algorithm>
#include <cmath>

#include "light/light.h"
#include "pathspace/connect.h"
#include "pathspace/subpath.h"
#include "scene/spawn.h"

namespace omega {

namespace {

// A smooth conductor: its only lobe is the delta reflection.
bool is_smooth_mirror(const Bsdf& b) {
    const auto* c = std::get_if<ConductorBsdf>(&b);
    return c && c->alpha_u == 0 && c->alpha_v == 0 && !c->alpha_tex;
}

std::optional<PlanarMirror> planar_mirror(const Scene& scene, uint32_t si) {
    const Shape& sh = scene.shapes()[si];
    if (sh.kind != ShapeKind::Triangles || sh.masked() || sh.bump_tex || sh.light >= 0) return std::nullopt;
    if (!is_smooth_mirror(scene.materials()[sh.material]) || sh.face_normals.empty()) return std::nullopt;
    const Vec3 n = sh.face_normals[0];
    for (const Vec3& fn : sh.face_normals)
        if (dot(fn, n) < 1.f - 1e-6f) return std::nullopt;
    for (const Vec3& vn : sh.mesh.normals)
        if (std::abs(dot(vn, n)) < 1.f - 1e-6f) return std::nullopt;  // smooth-shaded: not a plane mirror
    PlanarMirror m;
    m.shape = si;
    m.n = n;
    m.d = dot(n, sh.mesh.positions[sh.mesh.indices[0]]);
    float extent = 0;
    for (const Vec3& p : sh.mesh.positions) extent = std::max(extent, max_component(abs(p)));
    for (const Vec3& p : sh.mesh.positions)
        if (std::abs(m.side(p)) > 1e-5f * std::max(1.f, extent)) return std::nullopt;
    m.area = sh.area;
    return m;
}

// The mirror's delta reflection seen from direction `wo` (world, away from the mirror).
Rgb reflection_weight(const Scene& scene, const SurfaceHit& hit, const Vec3& wo, TransportMode mode) {
    Bsdf textured;
    const Bsdf& b = scene.bsdf_at(hit, textured);
    const Frame shading = Frame::from_normal(hit.ns);
    const Vec3 wo_local = shading.to_local(wo);
    if (wo_local.z == 0) return Rgb(0.f);
    auto bs = bsdf_sample(b, wo_local, 0.5f, {0.5f, 0.5f}, mode);
    if (!bs || !bs->is_delta()) return Rgb(0.f);
    return bs->weight;
}


}  // namespace

bool PlanarMirror::usable_from(const Vec3& p) const {
    return std::abs(side(p)) > 1e-4f * std::max(1.f, max_component(abs(p)));
}

PlanarMirrors find_planar_mirrors(const Scene& scene) {
    PlanarMirrors out;
    out.of_shape.assign(scene.shapes().size(), -1);
    std::vector<PlanarMirror> all;
    for (uint32_t i = 0; i < scene.shapes().size(); ++i)
        if (auto m = planar_mirror(scene, i)) all.push_back(*m);
    // The largest first (stable: equal areas keep the scene's order, so the choice is reproducible).
    std::stable_sort(all.begin(), all.end(), [](const PlanarMirror& a, const PlanarMirror& b) { return a.area > b.area; });
    if (all.size() > size_t(kMaxPlanarMirrors)) all.resize(size_t(kMaxPlanarMirrors));
    for (size_t i = 0; i < all.size(); ++i) out.of_shape[all[i].shape] = int8_t(i);
    out.list = std::move(all);
    return out;
}

std::optional<Vec3> plane_crossing(const PlanarMirror& m, const Vec3& a, const Vec3& b) {
    const float sa = m.side(a), sb = m.side(b);
    if (!(sa * sb < 0)) return std::nullopt;
    const float t = sa / (sa - sb);
    return a + (b - a) * t;
}

std::optional<MirrorBounce> bounce_off(const Scene& scene, const PlanarMirror& mirror, const SurfaceHit& from,
                                       const Vec3& m, TracerStats& stats) {
    const Vec3 d = m - from.p;
    const float len = length(d);
    if (!(len > 0)) return std::nullopt;
    const Vec3 w = d / len;
    SurfaceHit hit;
    ++stats.rays;
    if (!scene.intersect(spawn_ray(from, w), hit) || hit.shape != mirror.shape) return std::nullopt;
    MirrorBounce b;
    b.hit = hit;
    b.weight = reflection_weight(scene, hit, -w, TransportMode::Radiance);
    if (is_black(b.weight)) return std::nullopt;
    return b;
}

std::optional<LightChain> sample_light_chain(const Scene& scene, const PlanarMirror& mirror, const SurfaceHit& x,
                                             const Frame& shading, const Vec3& wo_local, const Bsdf& bsdf, Sampler& sampler,
                                             TracerStats& stats) {
    const auto& sel = scene.light_selection();
    if (sel.empty() || !mirror.usable_from(x.p)) return std::nullopt;
    const float u_sel = sampler.next_1d_if(sel.size() > 1);
    const Vec2 u = sampler.next_2d();
    const size_t li = sel.sample(u_sel);
    const float pmf = sel.pmf(li);
    const Light& light = scene.lights()[li];
    const Vec3 x_img = mirror.image(x.p);
    auto ls = light_sample_li(scene, light, x_img, u);
    if (!ls || ls->pdf_sa <= 0 || is_black(ls->Li)) return std::nullopt;
    // The straight segment from the image to the light crosses the plane at m; at infinity, the
    // ray from the image along wi does.
    std::optional<Vec3> m;
    if (ls->infinite) {
        const float dn = dot(mirror.n, ls->wi), t = -mirror.side(x_img) / dn;
        if (t > 0 && std::isfinite(t)) m = x_img + ls->wi * t;
    } else if (mirror.side(ls->p) * mirror.side(x.p) > 0) {  // not behind the mirror
        m = plane_crossing(mirror, x_img, ls->p);
    }
    if (!m) return std::nullopt;
    const Vec3 to_m = *m - x.p;
    const Vec3 w = to_m / length(to_m);
    const Vec3 wi_local = shading.to_local(w);
    if (!consistent_side(w, x.ng, wi_local.z)) return std::nullopt;
    const Rgb f = bsdf_eval(bsdf, wo_local, wi_local, TransportMode::Radiance) * std::abs(wi_local.z);
    if (is_black(f)) return std::nullopt;
    auto b = bounce_off(scene, mirror, x, *m, stats);
    if (!b) return std::nullopt;
    // The second leg, from the mirror point to the light.
    ++stats.rays;
    const Ray shadow = ls->infinite ? spawn_ray(b->hit, ls->wi) : spawn_ray_to(b->hit, ls->p, ls->p_error, ls->n);
    if (scene.occluded(shadow)) return std::nullopt;
    LightChain out;
    out.pdf_light_sa = pmf * ls->pdf_sa;
    out.delta_light = ls->delta;
    out.pdf_bsdf_sa = bsdf_pdf_sa(bsdf, wo_local, wi_local, TransportMode::Radiance);
    out.L = f * b->weight * ls->Li / out.pdf_light_sa;
    out.mirror = b->hit;
    out.light_vertex = light_sample_vertex(li, *ls);
    return out;
}

float mirror_light_pdf_sa(const Scene& scene, const PlanarMirror& mirror, const Vec3& x, size_t light,
                          const SurfaceHit& y_hit) {
    const auto* al = std::get_if<AreaLight>(&scene.lights()[light]);
    if (!al || !mirror.usable_from(x)) return 0.f;
    return scene.light_selection().pmf(light) * light_pdf_li_sa(scene, *al, mirror.image(x), y_hit);
}

float mirror_environment_pdf_sa(const Scene& scene, const PlanarMirror& mirror, const Vec3& x, size_t light, const Vec3& d) {
    if (!mirror.usable_from(x)) return 0.f;
    return scene.light_selection().pmf(light) * environment_pdf_li_sa(scene.lights()[light], d);
}

void mirror_connector_factors(const PlanarMirrors& mirrors, const std::vector<const PathVertex*>& v, FullPathPdfs& fp) {
    const int n = int(v.size());
    for (int j = 1; j + 1 < n; ++j) {
        const PathVertex& m = *v[size_t(j)];
        if (!fp.delta[size_t(j)] || m.kind != VertexKind::Surface || mirrors.index(m.hit.shape) < 0) continue;
        if (fp.delta[size_t(j - 1)] || fp.delta[size_t(j + 1)]) continue;
        const PathVertex &a = *v[size_t(j - 1)], &b = *v[size_t(j + 1)];
        if (b.infinite) continue;
        const Vec3 mn = mirrors.list[size_t(mirrors.index(m.hit.shape))].n;
        const Vec3 wb = b.p() - m.p();
        const double d1 = length(wb);
        const double cos_m = std::abs(dot(mn, wb)) / d1;
        double J;
        if (a.infinite) {
            J = b.is_on_surface() ? std::abs(dot(b.hit.ng, wb)) / d1 / cos_m : 1.0;
        } else {
            const Vec3 wa = a.p() - m.p();
            const double d0 = length(wa), R2 = (d0 + d1) * (d0 + d1);
            if (a.is_on_surface()) J = std::abs(dot(a.hit.ng, wa)) / d0 * d1 * d1 / (cos_m * R2);
            else if (b.is_on_surface()) J = std::abs(dot(b.hit.ng, wb)) / d1 * d0 * d0 / (cos_m * R2);
            else J = 1.0;  // point light to pinhole: the connector is the only strategy
        }
        if (!(J > 0) || !std::isfinite(J)) continue;
        if (fp.connector.empty()) fp.connector.assign(size_t(n), 0.0);
        fp.connector[size_t(j)] = J;
    }
}

namespace {

// The mirror vertex of a connector path (its densities are set by the caller).
PathVertex mirror_vertex(const Scene& scene, const SurfaceHit& hit) {
    PathVertex mv;
    mv.kind = VertexKind::Surface;
    mv.delta = true;
    mv.hit = hit;
    mv.shading = Frame::from_normal(hit.ns);
    mv.bsdf = &scene.materials()[scene.shapes()[hit.shape].material];
    return mv;
}

}  // namespace

std::optional<Connection> connect_via_mirror(const Scene& scene, int mi, const std::vector<PathVertex>& light,
                                             const std::vector<PathVertex>& camera, int s, int t, const StrategySet& set,
                                             Sampler& sampler, TracerStats& stats, ConnectStats& cstats,
                                             std::vector<PathVertex>* full_path, FullPathPdfs* pdfs) {
    if (!set.mirrors || !set.allows_connector(s, t)) return std::nullopt;
    const PlanarMirror& mirror = set.mirrors->list[size_t(mi)];
    Connection c;
    PathVertex sampled;  // the light (s = 1) or sensor (t = 1) endpoint sampled through the mirror
    const PathVertex* sampled_light = nullptr;
    const PathVertex* sampled_sensor = nullptr;
    SurfaceHit mhit;
    Rgb R;
    if (t == 1) {
        // The lens sampled from the image of y = light[s-1]; the splat lands where the camera
        // sees the mirror point.
        const PathVertex& y = light[size_t(s - 1)];
        if (!y.connectible() || y.infinite || !mirror.usable_from(y.p())) return std::nullopt;
        const Sensor& sensor = scene.sensor();
        sampler.start_dimension(dims::mirror_sensor(s, mi));
        auto sc = sensor.sample_wi(mirror.image(y.p()), sampler.next_2d_if(sensor.uses_lens_sample()));
        if (!sc || !(mirror.side(sc->p) * mirror.side(y.p()) > 0)) return std::nullopt;
        auto m = plane_crossing(mirror, mirror.image(y.p()), sc->p);
        if (!m) return std::nullopt;
        const Vec3 to_m = *m - y.p();
        const Vec3 w = to_m / length(to_m);
        if (y.kind == VertexKind::Light) {
            const Rgb le = light_emission_towards(scene.lights()[size_t(y.light)], y.hit, w);
            c.L = le * float(1.0 / light_endpoint_density(scene, y));
        } else {
            c.L = y.beta * vertex_f(y, w, TransportMode::Importance) * absdot(w, y.hit.ns);
        }
        if (is_black(c.L)) return std::nullopt;
        if (is_black(y.hit.ng)) {  // a point light: no surface to spawn from
            ++stats.rays;
            if (!scene.intersect(Ray{y.p(), w}, mhit) || mhit.shape != mirror.shape) return std::nullopt;
            R = reflection_weight(scene, mhit, -w, TransportMode::Importance);
            if (is_black(R)) return std::nullopt;
        } else {
            auto b = bounce_off(scene, mirror, y.hit, *m, stats);
            if (!b) return std::nullopt;
            mhit = b->hit;
            R = b->weight;
        }
        ++stats.rays;
        if (scene.occluded(spawn_ray_to(mhit, sc->p, Vec3(0.f), Vec3(0.f)))) return std::nullopt;
        // The unfolded distance |y - m| + |m - c| is |y' - c|: sample_wi's own.
        const double geo = sc->infinite_dir ? 1.0 : 1.0 / (double(sc->dist) * sc->dist);
        c.L = c.L * R * float(geo);
        c.splat = true;
        c.film = sc->film;
        c.importance = sc->importance;
        sampled = sensor_vertex(scene, sc->p);
        sampled.pdf_fwd = sensor.delta_direction() ? 1.0 : sensor.pdf_we(sc->p, -sc->wi).pos;
        sampled_sensor = &sampled;
    } else if (s == 1) {
        // Next-event estimation from z = camera[t-1] through the mirror.
        const PathVertex& z = camera[size_t(t - 1)];
        if (!z.connectible() || z.kind != VertexKind::Surface) return std::nullopt;
        Bsdf textured;
        const Bsdf& bsdf = resolve_bsdf(*z.bsdf, z.hit.uv, textured);
        sampler.start_dimension(dims::mirror_light(t - 1, mi));
        auto ls = sample_light_chain(scene, mirror, z.hit, z.shading, z.shading.to_local(z.wo), bsdf, sampler, stats);
        if (!ls) return std::nullopt;
        c.L = z.beta * ls->L;
        mhit = ls->mirror;
        sampled = ls->light_vertex;
        sampled_light = &sampled;
    } else {
        // Both ends given: the reflection point lies where y meets z's image.
        const PathVertex& y = light[size_t(s - 1)];
        const PathVertex& z = camera[size_t(t - 1)];
        if (!y.connectible() || !z.connectible() || y.kind != VertexKind::Surface || z.kind != VertexKind::Surface)
            return std::nullopt;
        if (!mirror.usable_from(y.p()) || !mirror.usable_from(z.p())) return std::nullopt;
        const Vec3 z_img = mirror.image(z.p());
        auto m = plane_crossing(mirror, y.p(), z_img);
        if (!m) return std::nullopt;
        const Vec3 wy = normalize(*m - y.p()), wz = normalize(*m - z.p());
        const Rgb fy = vertex_f(y, wy, TransportMode::Importance), fz = vertex_f(z, wz, TransportMode::Radiance);
        if (is_black(fy) || is_black(fz)) return std::nullopt;
        const float dist2 = length_sq(z_img - y.p());
        c.L = y.beta * fy * fz * z.beta * (absdot(wy, y.hit.ns) * absdot(wz, z.hit.ns) / dist2);
        if (is_black(c.L)) return std::nullopt;
        auto b = bounce_off(scene, mirror, y.hit, *m, stats);
        if (!b) return std::nullopt;
        mhit = b->hit;
        c.L *= b->weight;
        ++stats.rays;
        if (scene.occluded(spawn_ray_to(mhit, z.p(), z.hit.p_error, z.hit.ng))) return std::nullopt;
    }
    if (is_black(c.L)) return std::nullopt;

    // The table of the full path light[0..s) + m + reverse(camera[0..t)): m joins the camera
    // side (t + 1 vertices), so the connection edge is light[s-1] -- m.
    auto& cam = cstats.mirror_camera;
    if (t == 1) {
        cam.assign(1, PathVertex{});  // stands for the sampled sensor
    } else {
        cam.assign(camera.begin(), camera.begin() + t);
    }
    // The mirror vertex, with the camera side's density of generating it (area measure): the
    // lens sampled afresh (t = 1), or camera[t-1] scattering towards it.
    PathVertex mv = mirror_vertex(scene, mhit);
    const PathVertex& next = t == 1 ? sampled : camera[size_t(t - 1)];
    mv.pdf_fwd = t == 1 ? sensor_density_at(scene, next, mv) : to_area_density(next, vertex_pdf_sa(next, next.wo, direction(next, mv)), mv);
    mv.wo = direction(mv, next);
    cam.push_back(mv);
    FullPathPdfs& fp = cstats.table;
    full_path_pdfs_into(scene, light, cam, s, t + 1, sampled_light, sampled_sensor, fp, set.mirrors);
    // camera[t-2]'s density from the light side: generated at z = camera[t-1] having arrived
    // from the mirror, not from the vertex z's own walk went on to.
    if (t >= 2) {
        const PathVertex& z = camera[size_t(t - 1)];
        const PathVertex& z2 = camera[size_t(t - 2)];
        const PathVertex& mv = cam.back();
        fp.p_light[size_t(s + 2)] = to_area_density(z, vertex_pdf_sa(z, direction(z, mv), direction(z, z2)), z2);
    }
    const double w = mis_weight_connector(fp, s, set);
    if (w < 0) {
        ++cstats.bad_weights;
        return std::nullopt;
    }
    c.weight = w;
    if (full_path) assemble_full_path(light, camera, s, t, sampled_light, sampled_sensor, &cam.back(), *full_path);
    if (pdfs) *pdfs = fp;
    return c;
}

}  // namespace omega
