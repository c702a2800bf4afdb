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

// Each three-float field is followed by a four-byte one: the intersector's stores of a vector
// then cover its readers' 8-byte loads of x and y. Back to back, ng and ns were written by one
// 16-byte store (ng, ns.x) and one 8-byte store (ns.y, ns.z), and every bounce's load of ns.x,
// ns.y missed store forwarding.
struct SurfaceHit {
    Vec3 p;         // hit point
    float t = 0;
    Vec3 p_error;   // conservative absolute error bound of p, per axis
    uint32_t shape = 0;  // index into Scene::shapes()
    Vec3 ng;        // geometric normal (unit, after flip_normals)
    uint32_t prim = 0;
    Vec3 ns;        // shading normal (unit, same side as ng)
    bool planar = true;  // a triangle: cannot be hit again by a ray leaving it
    // Surface coordinates (Mitsuba's conventions per shape), filled only on shapes whose material
    // is textured, so untextured scenes pay nothing for them; (0, 0) elsewhere.
    Vec2 uv{};
};

}  // namespace omega
