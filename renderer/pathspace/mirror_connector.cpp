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

inline bool consistent_side(const Vec3& w_world, const Vec3& ng, float cos_shading) {
    return dot(w_world, ng) * cos_shading > 0;
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

std::optional<MirrorLightSample> sample_light_via_mirror(const Scene& scene, const PlanarMirror& mirror,
                                                         const SurfaceHit& x, const Frame& shading, const Vec3& wo_local,
                                                         const Bsdf& bsdf, Sampler& sampler, TracerStats& stats) {
    const auto& sel = scene.light_selection();
    if (sel.empty() || !mirror.usable_from(x.p)) return std::nullopt;
    const float u_sel = sampler.next_1d();
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
    MirrorLightSample out;
    out.pdf_light_sa = pmf * ls->pdf_sa;
    out.delta_light = ls->delta;
    out.pdf_bsdf_sa = bsdf_pdf_sa(bsdf, wo_local, wi_local, TransportMode::Radiance);
    out.L = f * b->weight * ls->Li / out.pdf_light_sa;
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

std::optional<MirrorSensorSplat> connect_sensor_via_mirror(const Scene& scene, const PlanarMirror& mirror,
                                                           const std::vector<PathVertex>& light, int s, Sampler& sampler,
                                                           TracerStats& stats) {
    const PathVertex& y = light[size_t(s - 1)];
    if (!y.connectible() || y.infinite || !mirror.usable_from(y.p())) return std::nullopt;
    const Sensor& sensor = scene.sensor();
    const Vec3 y_img = mirror.image(y.p());
    auto sc = sensor.sample_wi(y_img, sampler.next_2d());
    if (!sc) return std::nullopt;
    if (!(mirror.side(sc->p) * mirror.side(y.p()) > 0)) return std::nullopt;  // the camera is behind the mirror
    auto m = plane_crossing(mirror, y_img, sc->p);
    if (!m) return std::nullopt;
    const Vec3 to_m = *m - y.p();
    const Vec3 w = to_m / length(to_m);
    Rgb L;
    if (y.kind == VertexKind::Light) {
        const Rgb le = light_emission_towards(scene.lights()[size_t(y.light)], y.hit, w);
        L = le * float(1.0 / light_endpoint_density(scene, y));
    } else {
        L = y.beta * vertex_f(y, w, TransportMode::Importance) * absdot(w, y.hit.ns);
    }
    if (is_black(L)) return std::nullopt;
    // A point light or a pinhole has no surface to spawn from: start on the point itself.
    SurfaceHit from = y.hit;
    std::optional<MirrorBounce> b;
    if (is_black(y.hit.ng)) {
        SurfaceHit hit;
        ++stats.rays;
        Ray r{y.p(), w};
        if (!scene.intersect(r, hit) || hit.shape != mirror.shape) return std::nullopt;
        const Rgb R = reflection_weight(scene, hit, -w, TransportMode::Importance);
        if (is_black(R)) return std::nullopt;
        b = MirrorBounce{hit, R};
    } else {
        b = bounce_off(scene, mirror, from, *m, stats);
        if (!b) return std::nullopt;
    }
    ++stats.rays;
    if (scene.occluded(spawn_ray_to(b->hit, sc->p, Vec3(0.f), Vec3(0.f)))) return std::nullopt;
    // The unfolded distance |y - m| + |m - c| is |y' - c|: sample_wi's own.
    const double geo = sc->infinite_dir ? 1.0 : 1.0 / (double(sc->dist) * sc->dist);
    MirrorSensorSplat out;
    out.L = L * b->weight * float(geo * sc->importance);
    out.film = sc->film;
    return out;
}

}  // namespace omega
