// Embree queries. Rays leaving a planar primitive carry its id; a per-query context filter
// rejects a hit on that same primitive, which can only be a rounding artefact.
#include "scene/scene.h"

#include <cmath>
#include <stdexcept>

#include "math/float_bits.h"
#include "scene/sphere_geometry.h"

namespace omega {

namespace {

// The origin primitive of each ray of a query, found by the ray's id (its lane in a packet, 0
// for a single ray): one context serves a whole packet.
struct QueryContext {
    RTCIntersectContext ctx;  // must be first: Embree hands back a pointer to it
    uint32_t geom[Scene::kPacket], prim[Scene::kPacket];
};

void reject_self_hit(const RTCFilterFunctionNArguments* args) {
    const auto* qc = reinterpret_cast<const QueryContext*>(args->context);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        const unsigned lane = RTCRayN_id(args->ray, args->N, i);
        if (RTCHitN_geomID(args->hit, args->N, i) == qc->geom[lane] &&
            RTCHitN_primID(args->hit, args->N, i) == qc->prim[lane])
            args->valid[i] = 0;
    }
}

void init_context(QueryContext& qc, const Ray& ray, bool filter_self) {
    rtcInitIntersectContext(&qc.ctx);
    qc.geom[0] = ray.origin_geom;
    qc.prim[0] = ray.origin_prim;
    if (filter_self && ray.origin_geom != kNoPrimitive) qc.ctx.filter = reject_self_hit;
}

// A packet's context: every lane's origin, the self-hit filter where any lane has one (a lane
// without an origin has kNoPrimitive, which no hit's ids match).
void init_packet_context(QueryContext& qc, std::span<const Ray> rays, bool filter_self) {
    rtcInitIntersectContext(&qc.ctx);
    bool any = false;
    for (size_t i = 0; i < rays.size(); ++i) {
        qc.geom[i] = rays[i].origin_geom;
        qc.prim[i] = rays[i].origin_prim;
        any |= rays[i].origin_geom != kNoPrimitive;
    }
    if (filter_self && any) qc.ctx.filter = reject_self_hit;
}

void fill_ray(RTCRay& r, const Ray& ray) {
    r.org_x = ray.o.x; r.org_y = ray.o.y; r.org_z = ray.o.z;
    r.dir_x = ray.d.x; r.dir_y = ray.d.y; r.dir_z = ray.d.z;
    r.tnear = 0.f;
    r.tfar = ray.tmax;
    r.time = 0.f;
    r.mask = 0xffffffffu;
    r.id = 0;
    r.flags = 0;
}

// Lanes [0, rays.size()) of an 8-ray packet as fill_ray fills a single ray, id = lane; `valid`
// marks them, the other lanes stay out of the query.
void fill_packet(RTCRay8& r, int* valid, std::span<const Ray> rays) {
    for (size_t i = 0; i < Scene::kPacket; ++i) {
        valid[i] = i < rays.size() ? -1 : 0;
        if (i >= rays.size()) continue;
        const Ray& ray = rays[i];
        r.org_x[i] = ray.o.x; r.org_y[i] = ray.o.y; r.org_z[i] = ray.o.z;
        r.dir_x[i] = ray.d.x; r.dir_y[i] = ray.d.y; r.dir_z[i] = ray.d.z;
        r.tnear[i] = 0.f;
        r.tfar[i] = ray.tmax;
        r.time[i] = 0.f;
        r.mask[i] = 0xffffffffu;
        r.id[i] = unsigned(i);
        r.flags[i] = 0;
    }
}

// Mitsuba's sphere map: u = phi / 2 pi in [0, 1) around local z from +x, v = theta / pi from +z.
Vec2 sphere_uv(const Shape& sh, const Vec3& n_out) {
    Vec3 l{dot(n_out, sh.sphere_axes[0]), dot(n_out, sh.sphere_axes[1]), dot(n_out, sh.sphere_axes[2])};
    float u = std::atan2(l.y, l.x) * kInv2Pi;
    if (u < 0) u += 1.f;
    return {u, std::acos(std::clamp(l.z, -1.f, 1.f)) * kInvPi};
}

Vec2 triangle_uv(const Shape& sh, uint32_t i0, uint32_t i1, uint32_t i2, float b0, float b1, float b2) {
    const auto& uvs = sh.mesh.uvs;
    if (uvs.empty()) return {b1, b2};
    Vec2 uv{uvs[i0].x * b0 + uvs[i1].x * b1 + uvs[i2].x * b2, uvs[i0].y * b0 + uvs[i1].y * b1 + uvs[i2].y * b2};
    return sh.uv_map == UvMap::Disk ? disk_uv(uv) : uv;
}

// A uniform number in [0, 1) from the ray and the primitive it hits: the mask's coin. Any query
// of the same ray against the same triangle gets the same answer (renders stay deterministic
// and independent of thread timing), while different rays, whose origins and directions are
// continuous random variables of the path sampling, get independent-looking coins.
float mask_coin(const float o[3], const float d[3], uint32_t geom, uint32_t prim) {
    auto mix = [](uint64_t h) {  // splitmix64's finaliser
        h ^= h >> 30;
        h *= 0xbf58476d1ce4e5b9ull;
        h ^= h >> 27;
        h *= 0x94d049bb133111ebull;
        return h ^ (h >> 31);
    };
    uint64_t h = mix((uint64_t(geom) << 32) | prim);
    for (int k = 0; k < 3; ++k) {
        h = mix(h ^ std::bit_cast<uint32_t>(o[k]));
        h = mix(h ^ (uint64_t(std::bit_cast<uint32_t>(d[k])) << 17));
    }
    return float(h >> 40) * 0x1p-24f;
}

// Geometry filter of a masked triangle shape, for closest-hit and any-hit queries alike, so
// camera rays, walks, shadow rays and BDPT connections all see the same mask: a hit is kept with
// probability opacity(uv). A dropped hit is not a surface at all (no vertex, no density): the
// traversal just goes on behind it. Stochastic pass-through is unbiased for fractional opacity
// (bilinear edges of a binary mask): a walk passes with probability 1 - a and scatters with
// probability a, the factors of the measurement contribution a f and transmittance 1 - a, so
// both cancel; and since no strategy's density includes them, the MIS weights of all strategies
// are computed alike and still sum to one.
void mask_filter(const RTCFilterFunctionNArguments* args) {
    const auto* sh = static_cast<const Shape*>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        uint32_t prim = RTCHitN_primID(args->hit, args->N, i);
        float b1 = std::clamp(RTCHitN_u(args->hit, args->N, i), 0.f, 1.f);
        float b2 = std::clamp(RTCHitN_v(args->hit, args->N, i), 0.f, 1.f);
        float opacity = sh->opacity;
        if (sh->opacity_tex) {
            const auto& m = sh->mesh;
            uint32_t i0 = m.indices[3 * prim], i1 = m.indices[3 * prim + 1], i2 = m.indices[3 * prim + 2];
            opacity = sh->opacity_tex->eval(triangle_uv(*sh, i0, i1, i2, 1.f - b1 - b2, b1, b2)).x;
        }
        if (opacity >= 1.f) continue;
        if (opacity > 0.f) {
            float o[3] = {RTCRayN_org_x(args->ray, args->N, i), RTCRayN_org_y(args->ray, args->N, i),
                          RTCRayN_org_z(args->ray, args->N, i)};
            float d[3] = {RTCRayN_dir_x(args->ray, args->N, i), RTCRayN_dir_y(args->ray, args->N, i),
                          RTCRayN_dir_z(args->ray, args->N, i)};
            if (mask_coin(o, d, RTCHitN_geomID(args->hit, args->N, i), prim) < opacity) continue;
        }
        args->valid[i] = 0;
    }
}

// Mitsuba's bumpmap (bumpmap.cpp): with g = scale * grad_uv(height), the tangents become
// dp/du' = dp/du + n (g_u - n.dp/du) and likewise for v; the shading normal is their cross
// product, turned to the geometric normal's side. dp/du, dp/dv are the triangle's own, from its
// positions and uvs (a rectangle's dp/du is to_world (2, 0, 0), as Mitsuba's). The nested BSDF
// is then shaded in the tilted frame, and the walks' shading-normal correction (subpath.cpp,
// Veach's adjoint for shading normals) applies to it as to interpolated normals.
void apply_bump(const Shape& sh, uint32_t i0, uint32_t i1, uint32_t i2, SurfaceHit& hit) {
    const auto& m = sh.mesh;
    Vec2 t0{0, 0}, t1{1, 0}, t2{0, 1};  // no uvs: the barycentrics are the uvs (triangle_uv)
    if (!m.uvs.empty()) {
        t0 = m.uvs[i0];
        t1 = m.uvs[i1];
        t2 = m.uvs[i2];
    }
    Vec3 dp1 = m.positions[i1] - m.positions[i0], dp2 = m.positions[i2] - m.positions[i0];
    float d1u = t1.x - t0.x, d1v = t1.y - t0.y, d2u = t2.x - t0.x, d2v = t2.y - t0.y;
    float det = d1u * d2v - d1v * d2u;
    if (!(std::abs(det) > 0)) return;  // degenerate uv mapping: no tangents, keep the normal
    Vec3 dpdu = (dp1 * d2v - dp2 * d1v) / det, dpdv = (dp2 * d1u - dp1 * d2u) / det;
    Vec2 g = sh.bump_tex->eval_grad(hit.uv);
    const Vec3 n = hit.ns;
    Vec3 du = dpdu + n * (sh.bump_scale * g.x - dot(n, dpdu));
    Vec3 dv = dpdv + n * (sh.bump_scale * g.y - dot(n, dpdv));
    Vec3 nb = cross(du, dv);
    float len = length(nb);
    if (!(len > 0) || !std::isfinite(len)) return;
    nb = nb / len;
    hit.ns = dot(nb, hit.ng) < 0 ? -nb : nb;
}

}  // namespace

void attach_mask_filter(RTCGeometry g, const Shape& sh) {
    rtcSetGeometryUserData(g, const_cast<Shape*>(&sh));
    rtcSetGeometryIntersectFilterFunction(g, mask_filter);
    rtcSetGeometryOccludedFilterFunction(g, mask_filter);
}

Scene::~Scene() {
    if (rtc_) rtcReleaseScene(rtc_);
    if (device_) rtcReleaseDevice(device_);
}

// Inlined into both queries, so intersect()'s hot path stays the code it was: out of line, the
// path tracer read 3-5% slower in an A/B on a noisy machine (bench/ab_cores.sh).
[[gnu::always_inline]] inline void Scene::fill_hit(const Ray& ray, float t, uint32_t geom, uint32_t prim, float u, float v, SurfaceHit& hit) const {
    const Shape& sh = shapes_[geom];
    hit.t = t;
    hit.shape = geom;
    hit.prim = prim;
    if (sh.kind == ShapeKind::Sphere) {
        sphere_hit_point(sh.sphere.center, sh.sphere.radius, ray, hit.t, hit);
        if (sh.uv_map != UvMap::None) hit.uv = sphere_uv(sh, hit.ng);
        if (sh.flip_normals) {
            hit.ng = -hit.ng;
            hit.ns = -hit.ns;
        }
        hit.planar = false;
    } else {
        const auto& m = sh.mesh;
        uint32_t i0 = m.indices[3 * hit.prim], i1 = m.indices[3 * hit.prim + 1], i2 = m.indices[3 * hit.prim + 2];
        const Vec3 &p0 = m.positions[i0], &p1 = m.positions[i1], &p2 = m.positions[i2];
        float b1 = std::clamp(u, 0.f, 1.f), b2 = std::clamp(v, 0.f, 1.f);
        if (b1 + b2 > 1.f) {
            float s = b1 + b2;
            b1 /= s;
            b2 /= s;
        }
        float b0 = 1.f - b1 - b2;
        // Barycentric interpolation, with its bound (pbrt-v4 eq. 6.x: gamma_7 * sum |b_i p_i|),
        // the axes in one vector: the same roundings as p0 * b0 + p1 * b1 + p2 * b2 per axis.
        const F4 t0 = to_f4(p0) * b0, t1 = to_f4(p1) * b1, t2 = to_f4(p2) * b2;
        hit.p = to_vec3(t0 + t1 + t2);
        hit.p_error = to_vec3((abs4(t0) + abs4(t1) + abs4(t2)) * gamma_bound(7));
        Vec3 ng = sh.face_normals[hit.prim];
        if (!m.normals.empty()) {
            Vec3 ns = m.normals[i0] * b0 + m.normals[i1] * b1 + m.normals[i2] * b2;
            float len = length(ns);
            if (len > 0 && std::isfinite(len)) {
                ns = ns / len;
                // The shading normal decides orientation; keep the geometric one on its side.
                if (dot(ng, ns) < 0) ng = -ng;
                hit.ns = ns;
            } else {
                hit.ns = ng;
            }
        } else {
            hit.ns = ng;
        }
        hit.ng = ng;
        hit.planar = true;
        if (sh.uv_map != UvMap::None) hit.uv = triangle_uv(sh, i0, i1, i2, b0, b1, b2);
        if (sh.bump_tex) apply_bump(sh, i0, i1, i2, hit);
    }
}

bool Scene::intersect(const Ray& ray, SurfaceHit& hit) const {
    QueryContext qc;
    init_context(qc, ray, false);
    RTCRayHit rh;
    fill_ray(rh.ray, ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(rtc_, &qc.ctx, &rh);
    if (rh.hit.geomID == ray.origin_geom && rh.hit.primID == ray.origin_prim) {
        // A rounding-error hit on the planar primitive the ray leaves (about 1 ray in 1e6):
        // trace again with the filter, which is too costly to run on every closest-hit query.
        init_context(qc, ray, true);
        fill_ray(rh.ray, ray);
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(rtc_, &qc.ctx, &rh);
    }
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    fill_hit(ray, rh.ray.tfar, rh.hit.geomID, rh.hit.primID, rh.hit.u, rh.hit.v, hit);
    return true;
}

void Scene::intersect_packet(std::span<const Ray> rays, SurfaceHit* hits, bool* found) const {
    if (rays.size() > kPacket) throw std::logic_error("Scene::intersect_packet: more than kPacket rays");
    QueryContext qc;
    init_packet_context(qc, rays, false);
    alignas(32) int valid[kPacket];
    alignas(32) RTCRayHit8 rh;
    fill_packet(rh.ray, valid, rays);
    for (size_t i = 0; i < kPacket; ++i) {
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect8(valid, rtc_, &qc.ctx, &rh);
    for (size_t i = 0; i < rays.size(); ++i) {
        const uint32_t geom = rh.hit.geomID[i], prim = rh.hit.primID[i];
        if (geom != RTC_INVALID_GEOMETRY_ID && geom == rays[i].origin_geom && prim == rays[i].origin_prim) {
            found[i] = intersect(rays[i], hits[i]);  // the rare self-hit: intersect()'s own retry
            continue;
        }
        found[i] = geom != RTC_INVALID_GEOMETRY_ID;
        if (found[i]) fill_hit(rays[i], rh.ray.tfar[i], geom, prim, rh.hit.u[i], rh.hit.v[i], hits[i]);
    }
}

bool Scene::occluded(const Ray& ray) const {
    QueryContext qc;
    init_context(qc, ray, true);
    RTCRay r;
    fill_ray(r, ray);
    rtcOccluded1(rtc_, &qc.ctx, &r);
    return r.tfar < 0.f;
}

void Scene::occluded_packet(std::span<const Ray> rays, bool* occluded) const {
    if (rays.size() > kPacket) throw std::logic_error("Scene::occluded_packet: more than kPacket rays");
    QueryContext qc;
    init_packet_context(qc, rays, true);
    alignas(32) int valid[kPacket];
    alignas(32) RTCRay8 r;
    fill_packet(r, valid, rays);
    rtcOccluded8(valid, rtc_, &qc.ctx, &r);
    for (size_t i = 0; i < rays.size(); ++i) occluded[i] = r.tfar[i] < 0.f;
}

}  // namespace omega
