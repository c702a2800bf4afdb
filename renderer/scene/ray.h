#pragma once
// Rays and surface hits. Every ray that leaves a surface is made by spawn.h.
#include <cstdint>
#include <limits>

#include "math/vec.h"

namespace omega {

constexpr float kInfinity = std::numeric_limits<float>::infinity();
constexpr uint32_t kNoPrimitive = 0xffffffffu;

struct Ray {
    Vec3 o, d;
    float tmax = kInfinity;
    // The planar primitive the ray leaves, so Embree can skip a rounding-error self hit.
    uint32_t origin_geom = kNoPrimitive, origin_prim = kNoPrimitive;
};

struct SurfaceHit {
    Vec3 p;         // hit point
    Vec3 p_error;   // conservative absolute error bound of p, per axis
    Vec3 ng;        // geometric normal (unit, after flip_normals)
    Vec3 ns;        // shading normal (unit, same side as ng)
    float t = 0;
    uint32_t shape = 0;  // index into Scene::shapes()
    uint32_t prim = 0;
    bool planar = true;  // a triangle: cannot be hit again by a ray leaving it
    // Surface coordinates (Mitsuba's conventions per shape), filled only on shapes whose material
    // is textured, so untextured scenes pay nothing for them; (0, 0) elsewhere.
    Vec2 uv{};
};

}  // namespace omega
