#include "scene/sphere_geometry.h"

#include <cmath>
#include <stdexcept>

#include "math/float_bits.h"

namespace omega {

namespace {

// Both roots of |o + t d - c|^2 = r^2 in double, the stable form (no cancellation).
bool sphere_roots(const SphereData& s, const Vec3d& o, const Vec3d& d, double& t0, double& t1) {
    Vec3d oc = o - s.center;
    double a = dot(d, d);
    double b = 2.0 * dot(oc, d);
    // |oc|^2 - r^2 as (|oc| - r)(|oc| + r) keeps precision when the origin is on the sphere.
    double loc = length(oc);
    double c = (loc - s.radius) * (loc + s.radius);
    double disc = b * b - 4.0 * a * c;
    if (disc < 0) return false;
    double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
    if (q == 0) {
        t0 = t1 = 0;
        return a != 0;
    }
    t0 = q / a;
    t1 = c / q;
    if (t0 > t1) std::swap(t0, t1);
    return true;
}

void sphere_bounds(const RTCBoundsFunctionArguments* args) {
    const auto* s = static_cast<const SphereData*>(args->geometryUserPtr);
    RTCBounds* b = args->bounds_o;
    // Pad by a few ulps so float rounding of the box never clips the sphere.
    auto lo = [](double v) { return next_float_down(next_float_down(float(v))); };
    auto hi = [](double v) { return next_float_up(next_float_up(float(v))); };
    b->lower_x = lo(s->center.x - s->radius); b->upper_x = hi(s->center.x + s->radius);
    b->lower_y = lo(s->center.y - s->radius); b->upper_y = hi(s->center.y + s->radius);
    b->lower_z = lo(s->center.z - s->radius); b->upper_z = hi(s->center.z + s->radius);
}

// Lane i of a ray query and the roots of its line against the sphere (found: it meets it).
struct LaneRoots {
    Vec3d o, d;
    float tnear;
    bool found;
    double t0, t1;
};
LaneRoots lane_roots(const SphereData& s, RTCRayN* ray, unsigned N, unsigned i) {
    LaneRoots r;
    r.o = {RTCRayN_org_x(ray, N, i), RTCRayN_org_y(ray, N, i), RTCRayN_org_z(ray, N, i)};
    r.d = {RTCRayN_dir_x(ray, N, i), RTCRayN_dir_y(ray, N, i), RTCRayN_dir_z(ray, N, i)};
    r.tnear = RTCRayN_tnear(ray, N, i);
    r.found = sphere_roots(s, r.o, r.d, r.t0, r.t1);
    return r;
}

// Both callbacks serve single rays (N = 1) and Scene's packets (N = 8) alike, lane by lane with
// the same double arithmetic, so a packet's hits equal the single rays' bit for bit.
void sphere_intersect(const RTCIntersectFunctionNArguments* args) {
    const auto* s = static_cast<const SphereData*>(args->geometryUserPtr);
    const unsigned N = args->N;
    RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, N);
    RTCHitN* h = RTCRayHitN_HitN(args->rayhit, N);
    for (unsigned i = 0; i < N; ++i) {
        if (!args->valid[i]) continue;
        const LaneRoots r = lane_roots(*s, ray, N, i);
        if (!r.found) continue;
        float& tfar = RTCRayN_tfar(ray, N, i);
        const double t = r.t0 > r.tnear ? r.t0 : r.t1;
        if (!(t > r.tnear) || !(t < tfar)) continue;
        const Vec3d n = r.o + r.d * t - s->center;
        tfar = float(t);
        RTCHitN_Ng_x(h, N, i) = float(n.x); RTCHitN_Ng_y(h, N, i) = float(n.y); RTCHitN_Ng_z(h, N, i) = float(n.z);
        RTCHitN_u(h, N, i) = 0; RTCHitN_v(h, N, i) = 0;
        RTCHitN_primID(h, N, i) = args->primID;
        RTCHitN_geomID(h, N, i) = args->geomID;
        RTCHitN_instID(h, N, i, 0) = args->context->instID[0];
    }
}

void sphere_occluded(const RTCOccludedFunctionNArguments* args) {
    const auto* s = static_cast<const SphereData*>(args->geometryUserPtr);
    const unsigned N = args->N;
    RTCRayN* ray = args->ray;
    for (unsigned i = 0; i < N; ++i) {
        if (!args->valid[i]) continue;
        const LaneRoots r = lane_roots(*s, ray, N, i);
        if (!r.found) continue;
        float& tfar = RTCRayN_tfar(ray, N, i);
        if ((r.t0 > r.tnear && r.t0 < tfar) || (r.t1 > r.tnear && r.t1 < tfar)) tfar = -kInfinity;
    }
}

}  // namespace

void attach_sphere(RTCDevice device, RTCScene scene, unsigned geom_id, const SphereData* data) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, 1);
    rtcSetGeometryUserData(g, const_cast<SphereData*>(data));
    rtcSetGeometryBoundsFunction(g, sphere_bounds, nullptr);
    rtcSetGeometryIntersectFunction(g, sphere_intersect);
    rtcSetGeometryOccludedFunction(g, sphere_occluded);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene, g, geom_id);
    rtcReleaseGeometry(g);
}

void sphere_hit_point(const Vec3d& center, double radius, const Ray& ray, float t, SurfaceHit& hit) {
    Vec3d p = Vec3d(ray.o) + Vec3d(ray.d) * double(t);
    Vec3d n = normalize(p - center);
    p = center + n * radius;  // re-projection removes the error of o + t d
    hit.p = Vec3(p);
    // Rounding p (double) to float plus the re-projection's own error (pbrt-v4: gamma_5 |p|).
    hit.p_error = abs(hit.p) * gamma_bound(5);
    hit.ng = Vec3(n);
    hit.ns = hit.ng;
}

}  // namespace omega
