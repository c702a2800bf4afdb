#pragma once
// The plane of a one-sided planar emitter (a rectangle, a disk, any flat triangle mesh), so that
// next-event estimation from behind it is skipped: a one-sided light emits only to the side its
// face normals point to, so from a point behind its plane every light sample is refused
// (light_sample_li) and a shadow-rayless NEE costs its sampler draws, the point on the light and
// a square root for nothing. In a room lit from a lamp facing the ceiling that is most of the
// path tracer's vertices (scenes/indirect-room.yaml).
//
// behind() is conservative: it answers true only where light_sample_li refuses every u, with a
// tolerance that covers the mesh's deviation from one plane, the spread of its face normals and
// the rounding of each sample's point and direction. Skipping there changes no image: the same
// samples contribute, bit for bit.
#include <optional>
#include <vector>

#include "math/vec.h"
#include "scene/triangle_mesh.h"

namespace omega {

struct EmitterPlane {
    Vec3d o;               // a vertex of the mesh
    Vec3d n;               // unit; the side the face normals point to, which the light lights
    double deviation = 0;  // the most any vertex lies off the plane
    double spread = 0;     // the most any face normal differs from n (length of the difference)
    double extent = 0;     // the most any vertex lies from o
    // behind()'s tolerance, less its terms in ref: 2 deviation + (spread + 1e-4) extent + 1e-5 |o|,
    // and the factor of |o - ref|.
    double slack = 0, per_distance = 0;
};

// The plane of `m` when every vertex lies on it and every face normal (face_normals, one per
// triangle, unit) points the same way, to within 1e-4 of the mesh's size; else nullopt.
std::optional<EmitterPlane> find_emitter_plane(const TriangleMesh& m, const std::vector<Vec3>& face_normals);

// Whether `ref` lies behind the plane by more than the tolerance: no point of the emitter then
// faces it.
inline bool behind(const EmitterPlane& pl, const Vec3& ref) {
    const Vec3d r(ref);
    const Vec3d to_o = pl.o - r;
    const double side = dot(pl.n, to_o);
    if (!(side > 0)) return false;  // in front: the common case, and the cheap one
    // On the light's side a face normal f gives f.(p - ref) = f.(o - ref) + f.(p - o) >=
    // n.(o - ref) - spread (|o - ref| + extent) - deviation for every point p of the light; the
    // relative 1e-4 and 1e-5 terms leave room for the float rounding of p and of ref - p. The
    // 1-norm bounds |o - ref| from above without a square root.
    const Vec3d a = abs(to_o);
    const double tol = pl.slack + pl.per_distance * (a.x + a.y + a.z) + 1e-5 * max_component(abs(r));
    return side > tol;
}

}  // namespace omega
