#include "pathspace/mis_prefix.h"

#include <cmath>

#include "pathspace/connect.h"
#include "pathspace/subpath.h"
#include "scene/scene.h"

namespace omega {

EdgeDensities edge_densities(const Scene& scene, const PathVertex& a, const PathVertex* a2, const PathVertex& b,
                             const PathVertex* b2, int s, int t, const VertexLocal* la, const VertexLocal* lb,
                             const Sensor::Pdf* b_we) {
    EdgeDensities e;
    // The connection scatters at a and b through eval(), i.e. their non-delta lobes, whatever
    // lobe their own walks sampled next: a BSDF that mixes a delta lobe with others (smooth
    // plastic: mirror + substrate) may have recorded delta for the continuation that this path
    // does not take. pbrt-v3's MISWeight resets the same flags. Left as recorded for a delta-only
    // BSDF: eval() is 0 there, and every split keeps the same table.
    auto connected_delta = [](const PathVertex& v) {
        return v.delta && !(v.kind == VertexKind::Surface && v.bsdf && bsdf_has_nondelta(*v.bsdf));
    };
    e.a_delta = connected_delta(a);
    e.b_delta = connected_delta(b);
    // A density taken through a delta vertex is the discrete 1, as the walks record it. Only
    // impossible strategies connect there, but every split must yield the same table.
    auto through_a = [&](double pdf_area) { return e.a_delta ? 1.0 : pdf_area; };
    auto through_b = [&](double pdf_area) { return e.b_delta ? 1.0 : pdf_area; };
    // The walks' wo is direction(v, predecessor), computed from the same stored positions.
    // vertex_pdf_sa(v, from, to) is the BSDF's density between the two directions in v's frame.
    const Vec3 ab = direction(a, b);
    auto pdf = [](const PathVertex& v, const Vec3& from_l, const Vec3& to_l) {
        return double(bsdf_pdf_sa(*v.bsdf, from_l, to_l, TransportMode::Radiance));
    };
    VertexLocal local_a, local_b;
    if (s >= 2 && !la) la = &(local_a = {a.shading.to_local(a.wo), a.shading.to_local(ab)});
    if (t >= 2 && !lb) lb = &(local_b = {b.shading.to_local(b.wo), b.shading.to_local(-ab)});
    if (t == 1) e.sensor_a = b_we ? to_area_density(b, b_we->dir, a) : sensor_density_at(scene, b, a);
    else e.sensor_a = through_b(to_area_density(b, pdf(b, lb->wo, lb->w), a));
    if (a2) e.sensor_a2 = through_a(to_area_density(a, pdf(a, la->w, la->wo), *a2));
    if (s == 1) e.light_b = emission_density_at(scene, a, b);
    else e.light_b = through_a(to_area_density(a, pdf(a, la->wo, la->w), b));
    if (b2) e.light_b2 = through_b(to_area_density(b, pdf(b, lb->w, lb->wo), *b2));
    return e;
}

void MisPrefixes::prepare(const Scene& scene, const std::vector<PathVertex>& l, const std::vector<PathVertex>& c) {
    light = &l;
    camera = &c;
    n_light = l.size();
    n_camera = c.size();
    sensor_hittable = scene.sensor().lens_hittable();
    light_sum.resize(n_light);
    camera_sum.resize(n_camera);
    // delta[0] and delta[n-1] are 0 in the table: endpoints connect through their own sampling.
    if (n_light > 0) {
        light_hittable = !light_is_delta(scene.lights()[size_t(l[0].light)]);
        light_origin = light_endpoint_density(scene, l[0]);
        light_sum[0] = light_hittable ? 1.0 : 0.0;
        for (size_t m = 1; m < n_light; ++m) {
            const bool possible = !(m - 1 > 0 && l[m - 1].delta) && !l[m].delta;
            const double p_sensor = (m - 1 == 0 && !light_hittable) ? 0.0 : l[m - 1].pdf_rev;
            const double p_light = m - 1 == 0 ? light_origin : l[m - 1].pdf_fwd;
            const double r = p_sensor / p_light;
            light_sum[m] = (possible ? 1.0 : 0.0) + r * r * light_sum[m - 1];
        }
    }
    if (n_camera > 0) {
        camera_sum[0] = sensor_hittable ? 1.0 : 0.0;
        for (size_t q = 1; q < n_camera; ++q) {
            const bool possible = !(q - 1 > 0 && c[q - 1].delta) && !c[q].delta;
            const double r = c[q - 1].pdf_rev / c[q - 1].pdf_fwd;
            camera_sum[q] = (possible ? 1.0 : 0.0) + r * r * camera_sum[q - 1];
        }
    }
    ready = true;
}

double mis_weight_prefixed(const Scene& scene, const MisPrefixes& p, int s, int t, const EdgeDensities& e,
                           const PathVertex* sampled_light, const PathVertex* sampled_sensor) {
    const auto& L = *p.light;
    const auto& C = *p.camera;
    // Strategies with fewer light vertices: s - 1 and s - 2 from this connection's densities,
    // the rest from G[s-2].
    double down = 0;
    if (s >= 1) {
        const PathVertex& v0 = s == 1 && sampled_light ? *sampled_light : L[0];
        const bool v0_hittable = s == 1 && sampled_light ? !light_is_delta(scene.lights()[size_t(v0.light)])
                                                         : p.light_hittable;
        auto p_light = [&](int i) {
            if (i > 0) return L[size_t(i)].pdf_fwd;
            return s == 1 && sampled_light ? light_endpoint_density(scene, v0) : p.light_origin;
        };
        const double sensor_a = (s == 1 && !v0_hittable) ? 0.0 : e.sensor_a;
        const double r1 = sensor_a / p_light(s - 1);
        const bool possible = s == 1 ? v0_hittable : !(s - 2 > 0 && L[size_t(s - 2)].delta) && !e.a_delta;
        if (possible) down += r1 * r1;
        if (s >= 2) {
            const double sensor_a2 = (s == 2 && !p.light_hittable) ? 0.0 : e.sensor_a2;
            const double r2 = r1 * sensor_a2 / p_light(s - 2);
            down += r2 * r2 * p.light_sum[size_t(s - 2)];
        }
    }
    // Strategies with more light vertices: s + 1 and s + 2 from this connection's densities,
    // the rest from H[t-2].
    auto p_sensor = [&](int j) { return j == 0 && t == 1 && sampled_sensor ? sampled_sensor->pdf_fwd : C[size_t(j)].pdf_fwd; };
    double light_b, light_b2 = 0;
    bool b_delta;
    if (s == 0) {
        const PathVertex& v0 = C[size_t(t - 1)];
        light_b = light_endpoint_density(scene, v0);
        if (t >= 2) light_b2 = emission_density_at(scene, v0, C[size_t(t - 2)]);
        b_delta = false;
    } else {
        light_b = e.light_b;
        light_b2 = e.light_b2;
        b_delta = e.b_delta;
    }
    double up = 0;
    const double r1 = light_b / p_sensor(t - 1);
    const bool possible = t == 1 ? p.sensor_hittable : !b_delta && !(t - 2 > 0 && C[size_t(t - 2)].delta);
    if (possible) up += r1 * r1;
    if (t >= 2) {
        const double r2 = r1 * light_b2 / p_sensor(t - 2);
        up += r2 * r2 * p.camera_sum[size_t(t - 2)];
    }
    const double w = 1.0 / (1.0 + down + up);
    return std::isfinite(w) && w >= 0 ? w : -1.0;
}

}  // namespace omega
