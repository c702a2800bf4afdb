#include "light/emitter_plane.h"

#include <algorithm>

namespace omega {

std::optional<EmitterPlane> find_emitter_plane(const TriangleMesh& m, const std::vector<Vec3>& face_normals) {
    if (m.positions.empty() || face_normals.empty()) return std::nullopt;
    EmitterPlane pl;
    pl.o = Vec3d(m.positions[m.indices.empty() ? 0 : m.indices[0]]);
    pl.n = normalize(Vec3d(face_normals[0]));
    if (!(length(pl.n) > 0.5)) return std::nullopt;  // a degenerate first triangle
    for (const Vec3& f : face_normals) pl.spread = std::max(pl.spread, length(Vec3d(f) - pl.n));
    for (const Vec3& v : m.positions) {
        const Vec3d d = Vec3d(v) - pl.o;
        pl.deviation = std::max(pl.deviation, std::abs(dot(pl.n, d)));
        pl.extent = std::max(pl.extent, length(d));
    }
    // Folded, curved or two-faced meshes are not one plane; neither is anything non-finite.
    if (!(pl.spread <= 1e-4) || !(pl.deviation <= 1e-4 * pl.extent) || !std::isfinite(pl.extent)) return std::nullopt;
    pl.per_distance = pl.spread + 1e-4;
    pl.slack = 2 * pl.deviation + pl.per_distance * pl.extent + 1e-5 * max_component(abs(pl.o));
    return pl;
}

}  // namespace omega
