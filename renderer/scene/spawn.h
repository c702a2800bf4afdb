#pragma once
// The one way rays leave surfaces: the origin is pushed off the surface along the normal by the
// hit point's computed error bound, then rounded away from the surface (pbrt-v4, sec. 6.8.6).
// This holds at any scene scale because the bound scales with the coordinates themselves.
#include "math/float_bits.h"
#include "scene/ray.h"

namespace omega {

// The axes go through four-lane vectors (float_bits.h): the same roundings as the scalar
// p + n d and next_float_toward per axis, bit for bit (spawn_test checks it).
inline Vec3 offset_ray_origin(const Vec3& p, const Vec3& p_error, const Vec3& n, const Vec3& w) {
    const float d = dot(abs(n), p_error);
    F4 offset = to_f4(n) * d;
    if (dot(w, n) < 0) offset = (F4)((U4)offset ^ 0x80000000u);  // -offset, as a sign flip
    const F4 po = to_f4(p) + offset;
    return to_vec3((F4)next_float_toward4((U4)po, offset));
}

// A direction counts as leaving on the side the shading frame says only if the geometric normal
// agrees; otherwise interpolated normals would leak light through surfaces.
inline bool consistent_side(const Vec3& w_world, const Vec3& ng, float cos_shading) {
    return dot(w_world, ng) * cos_shading > 0;
}

inline Ray spawn_ray(const SurfaceHit& h, const Vec3& w) {
    Ray r;
    r.o = offset_ray_origin(h.p, h.p_error, h.ng, w);
    r.d = w;
    if (h.planar) {
        r.origin_geom = h.shape;
        r.origin_prim = h.prim;
    }
    return r;
}

// Fraction of the segment kept for shadow rays: the far end is itself offset off its surface.
constexpr float kShadowEpsilon = 1e-4f;

// Shadow ray from a surface to a point (lights: area samples carry their own error bound).
inline Ray spawn_ray_to(const SurfaceHit& from, const Vec3& p_to, const Vec3& p_to_error,
                        const Vec3& n_to) {
    Vec3 pf = offset_ray_origin(from.p, from.p_error, from.ng, p_to - from.p);
    Vec3 pt = p_to;
    if (!is_black(n_to)) pt = offset_ray_origin(p_to, p_to_error, n_to, pf - p_to);
    Ray r;
    r.o = pf;
    r.d = pt - pf;
    r.tmax = 1.f - kShadowEpsilon;
    if (from.planar) {
        r.origin_geom = from.shape;
        r.origin_prim = from.prim;
    }
    return r;
}

}  // namespace omega
