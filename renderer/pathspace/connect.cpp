#include "pathspace/connect.h"

#include <cmath>

#include "light/light_emission.h"
#include "pathspace/mirror_connector.h"
#include "pathspace/mis_prefix.h"
#include "scene/spawn.h"

namespace omega {

namespace {

// Density (solid angle) with which light `li`'s emission sampling leaves v0 towards w.
double emission_pdf_dir(const Scene& scene, const PathVertex& v0, const Vec3& w, double* pdf_pos = nullptr) {
    double pp, pd;
    light_pdf_le(scene, scene.lights()[size_t(v0.light)], v0.hit.ng, w, pp, pd);
    if (pdf_pos) *pdf_pos = pp;
    return pd;
}


// Density of the light endpoint v0 from the light side (selection x position, or direction at infinity).
double light_origin_density(const Scene& scene, const PathVertex& v0) {
    double pmf = scene.light_selection().pmf(size_t(v0.light));
    const Light& l = scene.lights()[size_t(v0.light)];
    if (v0.infinite) return pmf * infinite_light_pdf_dir(l, v0.dir) + (std::holds_alternative<DirectionalLight>(l) ? pmf : 0.0);
    if (light_is_delta(l)) return pmf;
    double pp = 0;
    emission_pdf_dir(scene, v0, Vec3{0, 0, 1}, &pp);
    return pmf * pp;
}

}  // namespace

double light_endpoint_density(const Scene& scene, const PathVertex& v0) { return light_origin_density(scene, v0); }

PathVertex light_sample_vertex(size_t light, const LightSample& ls) {
    PathVertex v;
    v.kind = VertexKind::Light;
    v.light = int(light);
    v.infinite = ls.infinite;
    v.dir = -ls.wi;
    v.hit.p = ls.p;
    v.hit.planar = false;
    v.hit.ng = ls.n;
    v.hit.p_error = ls.p_error;
    return v;
}

void assemble_full_path(const std::vector<PathVertex>& light, const std::vector<PathVertex>& camera, int s, int t,
                        const PathVertex* sampled_light, const PathVertex* sampled_sensor, const PathVertex* mirror,
                        std::vector<PathVertex>& out) {
    out.clear();
    for (int i = 0; i < s; ++i) out.push_back((i == 0 && sampled_light) ? *sampled_light : light[size_t(i)]);
    if (mirror) out.push_back(*mirror);
    for (int j = t - 1; j >= 0; --j) out.push_back((j == 0 && sampled_sensor) ? *sampled_sensor : camera[size_t(j)]);
}

FullPathPdfs full_path_pdfs(const Scene& scene, const std::vector<PathVertex>& light,
                            const std::vector<PathVertex>& camera, int s, int t, const PathVertex* sampled_light,
                            const PathVertex* sampled_sensor, const PlanarMirrors* mirrors) {
    FullPathPdfs fp;
    full_path_pdfs_into(scene, light, camera, s, t, sampled_light, sampled_sensor, fp, mirrors);
    return fp;
}

void full_path_pdfs_into(const Scene& scene, const std::vector<PathVertex>& light,
                         const std::vector<PathVertex>& camera, int s, int t, const PathVertex* sampled_light,
                         const PathVertex* sampled_sensor, FullPathPdfs& fp, const PlanarMirrors* mirrors) {
    const int n = s + t;
    fp.p_light.resize(size_t(n));
    fp.p_sensor.resize(size_t(n));
    fp.delta.assign(size_t(n), 0);
    // t = 0: the light side's last vertex is the lens (sampled_sensor, or light[s-1] itself).
    auto V = [&](int i) -> const PathVertex& {
        if (t == 0 && i == n - 1 && sampled_sensor) return *sampled_sensor;
        if (i < s) return (i == 0 && sampled_light) ? *sampled_light : light[size_t(i)];
        int j = t - 1 - (i - s);
        return (j == 0 && sampled_sensor) ? *sampled_sensor : camera[size_t(j)];
    };
    for (int i = 0; i < n; ++i) {
        const PathVertex& v = V(i);
        fp.p_light[size_t(i)] = i < s ? v.pdf_fwd : v.pdf_rev;
        fp.p_sensor[size_t(i)] = i < s ? v.pdf_rev : v.pdf_fwd;
        fp.delta[size_t(i)] = v.delta ? 1 : 0;
    }
    // Endpoints are never S in the sense of a scattering event; their own sampling connects them.
    fp.delta[0] = 0;
    fp.delta[size_t(n - 1)] = 0;

    const PathVertex& v0 = V(0);
    const Light& light0 = scene.lights()[size_t(v0.light)];
    fp.light_hittable = !light_is_delta(light0);
    fp.light_at_infinity = v0.infinite;
    fp.sensor_hittable = scene.sensor().lens_hittable();
    fp.p_light[0] = light_origin_density(scene, v0);
    auto through = [](const PathVertex& v, double pdf_area) { return v.delta ? 1.0 : pdf_area; };

    // Densities across the connecting edge v_{s-1} -- v_s and one step beyond, which neither
    // subpath could know when it was generated.
    if (s >= 1 && t >= 1) {
        const PathVertex& a = V(s - 1);  // light side
        const PathVertex& b = V(s);      // sensor side
        const EdgeDensities e = edge_densities(scene, a, s >= 2 ? &V(s - 2) : nullptr, b, t >= 2 ? &V(s + 1) : nullptr, s, t);
        if (s - 1 > 0) fp.delta[size_t(s - 1)] = e.a_delta ? 1 : 0;
        if (s < n - 1) fp.delta[size_t(s)] = e.b_delta ? 1 : 0;
        fp.p_sensor[size_t(s - 1)] = e.sensor_a;
        if (s >= 2) fp.p_sensor[size_t(s - 2)] = e.sensor_a2;
        fp.p_light[size_t(s)] = e.light_b;
        if (t >= 2) fp.p_light[size_t(s + 1)] = e.light_b2;
    } else if (t == 0 && n >= 2) {
        // The light subpath hit the lens b = v_k: the sensor side's densities at the end of the
        // path, which the light walk could not know (as for s = 0 at the other end).
        const PathVertex& b = V(n - 1);
        const PathVertex& a = V(n - 2);
        fp.p_sensor[size_t(n - 1)] = scene.sensor().pdf_we(b.p(), direction(b, a)).pos;
        fp.p_sensor[size_t(n - 2)] = sensor_density_at(scene, b, a);
        if (n >= 3) {
            const PathVertex& a2 = V(n - 3);
            fp.p_sensor[size_t(n - 3)] = through(a, to_area_density(a, vertex_pdf_sa(a, direction(a, b), direction(a, a2)), a2));
        }
    } else if (s == 0) {
        // The sensor subpath hit the light: v0 = camera[t-1]. The light side generates v1 by emission.
        if (t >= 2) fp.p_light[1] = emission_density_at(scene, v0, V(1));
    }
    // A light that cannot be hit has no density from the sensor side.
    if (!fp.light_hittable) fp.p_sensor[0] = 0;
    fp.connector.clear();
    if (mirrors) {
        fp.vertices.resize(size_t(n));
        for (int i = 0; i < n; ++i) fp.vertices[size_t(i)] = &V(i);
        mirror_connector_factors(*mirrors, fp.vertices, fp);
    }
}

std::optional<Connection> connect_lens(const Scene& scene, const std::vector<PathVertex>& light,
                                       const LensCrossing& lc, const StrategySet& set, ConnectStats& cstats,
                                       FullPathPdfs* pdfs) {
    const int s = lc.s + 1;  // the lens counts as the light side's last vertex
    if (!set.allows(s, 0) || lc.s < 1) return std::nullopt;
    Connection c;
    c.L = lc.beta;  // times W_e, applied per pixel through `importance` like a t = 1 splat
    if (is_black(c.L)) return std::nullopt;
    FullPathPdfs& fp = cstats.table;
    full_path_pdfs_into(scene, light, {}, s, 0, nullptr, &lc.lens, fp, set.mirrors);
    double w = mis_weight(fp, s, set);
    if (w < 0) {
        ++cstats.bad_weights;
        return std::nullopt;
    }
    c.weight = w;
    c.splat = true;
    c.film = lc.film;
    c.importance = lc.importance;
    if (pdfs) *pdfs = fp;
    return c;
}

std::optional<Connection> connect(const Scene& scene, const std::vector<PathVertex>& light,
                                  const std::vector<PathVertex>& camera, int s, int t, const StrategySet& set,
                                  Sampler& sampler, TracerStats& stats, ConnectStats& cstats,
                                  std::vector<PathVertex>* full_path, FullPathPdfs* pdfs) {
    Connection c;
    VertexLocal ly, lz;  // s, t >= 2: both ends in their shading frames, for f and the densities
    // Only s = 1 and t = 1 sample an endpoint (into cstats.sampled): most connections skip it.
    const PathVertex* sampled_light = nullptr;
    const PathVertex* sampled_sensor = nullptr;
    std::optional<Sensor::Pdf> sensor_we;  // t = 1: the sensor's pdf_we towards y, read again by the MIS weight
    if (s == 0) {
        // The camera subpath's last vertex is on a light.
        if (t < 2) return std::nullopt;
        const PathVertex& z = camera[size_t(t - 1)];
        if (z.light < 0) return std::nullopt;
        const Light& l = scene.lights()[size_t(z.light)];
        if (z.infinite) {
            if (!is_environment(l)) return std::nullopt;
            c.L = z.beta * environment_le(l, -z.dir);  // z.dir is the direction light travels
        } else {
            c.L = z.beta * area_light_le(std::get<AreaLight>(l), z.hit, z.wo);
        }
    } else if (t == 1) {
        // Connect a light vertex to the sensor (light tracing).
        const PathVertex& y = light[size_t(s - 1)];
        if (!y.connectible() || y.infinite) return std::nullopt;
        const Sensor& sensor = scene.sensor();
        sampler.start_dimension(dims::connect_sensor(s));
        auto sc = sensor.sample_wi(y.p(), sampler.next_2d_if(sensor.uses_lens_sample()));
        if (!sc) return std::nullopt;
        if (!set.single_strategy() || full_path || pdfs) {  // only the MIS weight and the tests read it
            PathVertex& sampled = cstats.sampled;
            sampled = sensor_vertex(scene, sc->p);
            if (sensor.delta_direction()) {
                sampled.pdf_fwd = 1.0;
            } else {
                sensor_we = sensor.pdf_we(sc->p, -sc->wi);
                sampled.pdf_fwd = sensor_we->pos;
            }
            sampled_sensor = &sampled;
        }
        if (y.kind == VertexKind::Light) {
            // s = 1: the light itself seen by the sensor. Emission towards the sensor over the
            // density of the light endpoint (selection x position).
            Rgb le = light_emission_towards(scene.lights()[size_t(y.light)], y.hit, sc->wi);
            c.L = le * float(1.0 / light_origin_density(scene, y));
        } else {
            c.L = y.beta * vertex_f(y, sc->wi, TransportMode::Importance) * absdot(sc->wi, y.hit.ns);
        }
        if (is_black(c.L)) return std::nullopt;
        double geo = sc->infinite_dir ? 1.0 : 1.0 / (double(sc->dist) * sc->dist);
        c.L *= float(geo);
        ++stats.rays;
        Ray shadow = is_black(y.hit.ng) ? Ray{y.p(), sc->p - y.p(), 1.f - kShadowEpsilon}
                                        : spawn_ray_to(y.hit, sc->p, Vec3(0.f), Vec3(0.f));
        if (scene.occluded(shadow)) return std::nullopt;
        c.splat = true;
        c.film = sc->film;
        c.importance = sc->importance;
    } else if (s == 1) {
        // Next-event estimation: sample a point on a light from the camera vertex.
        const PathVertex& z = camera[size_t(t - 1)];
        if (!z.connectible() || z.kind != VertexKind::Surface) return std::nullopt;
        const auto& sel = scene.light_selection();
        if (sel.empty()) return std::nullopt;
        sampler.start_dimension(dims::connect_light(t));
        size_t li = sel.sample(sampler.next_1d_if(sel.size() > 1));
        const Light& l = scene.lights()[li];
        if (light_faces_away(scene, l, z.p())) {  // every light sample would be refused
            sampler.skip_2d();
            return std::nullopt;
        }
        double pmf = sel.pmf(li);
        auto ls = light_sample_li(scene, l, z.p(), sampler.next_2d());
        if (!ls || ls->pdf_sa <= 0 || is_black(ls->Li)) return std::nullopt;
        cstats.sampled = light_sample_vertex(li, *ls);
        sampled_light = &cstats.sampled;
        Rgb f = vertex_f(z, ls->wi, TransportMode::Radiance) * absdot(ls->wi, z.hit.ns);
        if (is_black(f)) return std::nullopt;
        c.L = z.beta * f * ls->Li / float(pmf * ls->pdf_sa);
        ++stats.rays;
        Ray shadow = ls->infinite ? spawn_ray(z.hit, ls->wi) : spawn_ray_to(z.hit, ls->p, ls->p_error, ls->n);
        if (scene.occluded(shadow)) return std::nullopt;
    } else {
        const PathVertex& y = light[size_t(s - 1)];
        const PathVertex& z = camera[size_t(t - 1)];
        if (!y.connectible() || !z.connectible() || y.kind != VertexKind::Surface || z.kind != VertexKind::Surface)
            return std::nullopt;
        Vec3 d = z.p() - y.p();
        float dist2 = length_sq(d);
        if (!(dist2 > 0)) return std::nullopt;
        Vec3 w = d / std::sqrt(dist2);  // = direction(y, z), bit for bit
        ly = {y.shading.to_local(y.wo), y.shading.to_local(w)};
        lz = {z.shading.to_local(z.wo), z.shading.to_local(-w)};
        Rgb fy = vertex_f(y, w, ly, TransportMode::Importance);
        Rgb fz = vertex_f(z, -w, lz, TransportMode::Radiance);
        if (is_black(fy) || is_black(fz)) return std::nullopt;
        float g = absdot(w, y.hit.ns) * absdot(w, z.hit.ns) / dist2;
        c.L = y.beta * fy * fz * z.beta * g;
        if (is_black(c.L)) return std::nullopt;
        ++stats.rays;
        if (scene.occluded(spawn_ray_to(y.hit, z.p(), z.hit.p_error, z.hit.ng))) return std::nullopt;
    }
    if (is_black(c.L)) return std::nullopt;
    if (set.single_strategy() && !full_path && !pdfs) {
        c.weight = 1.0;  // what mis_weight gives: 1 / (1 + nothing)
        return c;
    }

    double w;
    if (!full_path && !pdfs && s + t >= 3 && set.type == IntegratorType::Bdpt && !set.mirrors &&
        cstats.prefix.covers(light, camera)) {
        // BDPT's common case: no table, the subpaths' sums beyond the edge (pathspace/mis_prefix.h).
        const PathVertex& a = s == 0 ? camera[size_t(t - 1)] : (s == 1 && sampled_light ? *sampled_light : light[size_t(s - 1)]);
        const PathVertex& b = t == 1 && sampled_sensor ? *sampled_sensor : camera[size_t(t - 1)];
        // Initialised by the call itself: assigned after a default construction, the result was
        // copied over with a `rep movsb`, a stall in every connection.
        const EdgeDensities e =
            s >= 1 ? edge_densities(scene, a, s >= 2 ? &light[size_t(s - 2)] : nullptr, b,
                                    t >= 2 ? &camera[size_t(t - 2)] : nullptr, s, t, s >= 2 && t >= 2 ? &ly : nullptr,
                                    s >= 2 && t >= 2 ? &lz : nullptr, sensor_we ? &*sensor_we : nullptr)
                   : EdgeDensities{};
        w = mis_weight_prefixed(scene, cstats.prefix, s, t, e, sampled_light, sampled_sensor);
    } else {
        FullPathPdfs& fp = cstats.table;
        full_path_pdfs_into(scene, light, camera, s, t, sampled_light, sampled_sensor, fp, set.mirrors);
        w = mis_weight(fp, s, set);
    }
    if (w < 0) {
        ++cstats.bad_weights;
        return std::nullopt;
    }
    c.weight = w;
    if (full_path) {
        assemble_full_path(light, camera, s, t, sampled_light, sampled_sensor, nullptr, *full_path);
        // This path scatters at the connection through eval(), not through the lobe the subpaths'
        // walks took next (see full_path_pdfs_into).
        for (int i : {s - 1, s})
            if (s >= 1 && t >= 1 && i >= 0 && i < s + t) {
                PathVertex& v = (*full_path)[size_t(i)];
                if (v.kind == VertexKind::Surface && v.bsdf && bsdf_has_nondelta(*v.bsdf)) v.delta = false;
            }
    }
    if (pdfs) *pdfs = cstats.table;
    return c;
}

}  // namespace omega
