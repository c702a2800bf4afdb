#pragma once
// Analytic spheres as Embree user geometry, intersected in double precision so that hits stay
// accurate far from the origin (scene scales up to 1e6).
#include <embree3/rtcore.h>

#include "math/vec.h"
#include "scene/ray.h"

namespace omega {

struct SphereData {
    Vec3d center;
    double radius;
};

// Adds one sphere as geometry `geom_id` of `scene`; `data` must outlive the scene.
void attach_sphere(RTCDevice device, RTCScene scene, unsigned geom_id, const SphereData* data);

// Re-projects the hit at parameter t onto the sphere and fills p, p_error and the outward normal.
void sphere_hit_point(const Vec3d& center, double radius, const Ray& ray, float t, SurfaceHit& hit);

}  // namespace omega
