#pragma once
// A point uniform by area (density 1 / area, area measure) on a triangle shape: as its
// parallelogram when it is one, else a triangle picked by area and a point uniform in it. The
// one routine behind next-event estimation and light subpaths, so both draw the same points.
#include <algorithm>

#include "math/float_bits.h"
#include "sampling/warp.h"
#include "scene/scene.h"

namespace omega {

inline AreaPoint sample_shape_area(const Shape& sh, Vec2 u) {
    if (sh.parallelogram) return sample_parallelogram(*sh.parallelogram, u);
    float u_tri;
    const size_t t = sh.tri_by_area.sample(u.x, &u_tri);
    const Vec2 b = square_to_uniform_triangle({u_tri, u.y});
    const auto& m = sh.mesh;
    const Vec3 &p0 = m.positions[m.indices[3 * t]], &p1 = m.positions[m.indices[3 * t + 1]],
               &p2 = m.positions[m.indices[3 * t + 2]];
    const float b2 = std::max(0.f, 1.f - b.x - b.y);
    AreaPoint s;
    s.p = p0 * b.x + p1 * b.y + p2 * b2;
    s.p_error = (abs(p0 * b.x) + abs(p1 * b.y) + abs(p2 * b2)) * gamma_bound(6);
    s.tri = uint32_t(t);
    return s;
}

}  // namespace omega
