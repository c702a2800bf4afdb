#pragma once
// A two-triangle shape that is a parallelogram (every rectangle, and a quad from a file when it
// is one) is sampled by area as the parallelogram: p = o + a e1 + b e2 for (a, b) uniform in
// [0, 1]^2. That is the same density (1 / area) as picking a triangle by area and then a point in
// it, without the pick's remapped number, its double division and the triangle warp's branch, and
// the sampler's 2D stratification reaches the whole light instead of each half.
#include <cstdint>
#include <optional>

#include "math/float_bits.h"
#include "math/vec.h"
#include "scene/triangle_mesh.h"

namespace omega {

struct Parallelogram {
    Vec3 o, e1, e2;        // corners o, o + e1, o + e1 + e2, o + e2
    uint32_t tri_a = 0;    // the triangle holding the points with a >= b: (o, o + e1, o + e1 + e2)
    uint32_t tri_b = 0;    // the one with b > a: (o, o + e1 + e2, o + e2)
    // Per axis, the most that o + e1, o + e2 and o + e1 + e2 miss the mesh's own vertices by
    // (rounding in the baked transform and in e1, e2), added to each sampled point's error bound.
    Vec3 slack{0.f, 0.f, 0.f};
};

// The parallelogram a mesh of exactly two triangles forms when they share an edge, face the same
// way and their far corners sum, within rounding, to the shared ones (the diagonals bisect each
// other). Anything else: nullopt, and the shape keeps sampling by triangle.
std::optional<Parallelogram> find_parallelogram(const TriangleMesh& m);

struct AreaPoint {
    Vec3 p, p_error;
    uint32_t tri;  // the triangle the point lies in
};

// Uniform by area (density 1 / area in area measure) for u uniform in [0, 1)^2.
inline AreaPoint sample_parallelogram(const Parallelogram& q, Vec2 u) {
    const Vec3 a1 = q.e1 * u.x, b2 = q.e2 * u.y;
    AreaPoint s;
    s.p = q.o + a1 + b2;
    // Two products and two sums: within gamma_3 of o + a e1 + b e2 (gamma_6, as the triangle path
    // allows), plus how far that ideal parallelogram lies from the mesh's corners.
    s.p_error = (abs(q.o) + abs(a1) + abs(b2)) * gamma_bound(6) + q.slack;
    s.tri = u.x >= u.y ? q.tri_a : q.tri_b;
    return s;
}

}  // namespace omega
