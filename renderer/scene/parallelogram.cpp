#include "scene/parallelogram.h"

#include <algorithm>
#include <cmath>

namespace omega {

namespace {

// How far the parallelogram may miss a mesh vertex and still be taken for it, relative to the
// coordinates' magnitude: a few roundings of a baked transform, far below any real quad's skew.
constexpr double kRelativeSlack = 16.0 * 0x1p-24;

}  // namespace

std::optional<Parallelogram> find_parallelogram(const TriangleMesh& m) {
    if (m.triangle_count() != 2) return std::nullopt;
    const uint32_t* t0 = &m.indices[0];
    const uint32_t* t1 = &m.indices[3];
    // The shared edge (i, j) in t0's order: t0 = (i, j, far0) up to rotation. A consistently wound
    // pair crosses that edge as (j, i) in t1.
    for (int r = 0; r < 3; ++r) {
        const uint32_t i = t0[r], j = t0[(r + 1) % 3], far0 = t0[(r + 2) % 3];
        for (int s = 0; s < 3; ++s) {
            if (t1[s] != j || t1[(s + 1) % 3] != i) continue;
            const uint32_t far1 = t1[(s + 2) % 3];
            if (far1 == far0 || far1 == i || far1 == j) return std::nullopt;
            // Corners in order: i, far1, j, far0 (t0 = (i, j, far0), t1 = (j, i, far1)). With
            // o = i, e1 = far1 - i, e2 = far0 - i, the corner o + e1 + e2 is j.
            const Vec3d pi(m.positions[i]), pj(m.positions[j]), pf0(m.positions[far0]), pf1(m.positions[far1]);
            Parallelogram q;
            q.o = m.positions[i];
            q.e1 = m.positions[far1] - m.positions[i];
            q.e2 = m.positions[far0] - m.positions[i];
            const Vec3d e1(q.e1), e2(q.e2);
            const auto max3 = [](const Vec3d& a, const Vec3d& b) {
                return Vec3d(std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z));
            };
            const Vec3d worst = max3(max3(abs(pi + e1 - pf1), abs(pi + e2 - pf0)), abs(pi + e1 + e2 - pj));
            const double scale = max_component(abs(pi) + abs(pj) + abs(pf0) + abs(pf1));
            if (!(max_component(worst) <= kRelativeSlack * scale)) return std::nullopt;
            const double area = length(cross(e1, e2));
            if (!(area > 0) || !std::isfinite(area)) return std::nullopt;
            // (i, far1, j) holds a >= b: it is (o, o + e1, o + e1 + e2). That is t1 = (j, i, far1).
            q.tri_a = 1;
            q.tri_b = 0;
            // Rounded up to float, then doubled: the bound must not shrink in the conversion.
            q.slack = Vec3(worst) * 2.f;
            return q;
        }
    }
    return std::nullopt;
}

}  // namespace omega
