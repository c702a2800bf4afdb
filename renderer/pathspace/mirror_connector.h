#pragma once
// The planar-mirror connector (Veach §8.3.4, the virtual-image construction): a D-S-D chain
// through one perfectly specular plane, which no local strategy samples when one end is a delta
// endpoint (a point light seen in a mirror, a floor lit only by a beam's reflection). Reflecting
// one end in the plane turns the chain into a straight segment: the other end samples towards
// the image as it would towards the real thing, and the segment crosses the plane at the
// reflection point m. The chain's density is then the endpoint sampler's density at the image,
// in the same measure the ordinary connection uses (solid angle at the image for lights, the
// sensor's own importance for cameras), since the reflection preserves solid angle and the
// unfolded length |x - m| + |m - y| = |x' - y|.
//
// Which integrators use it, and how it is weighed, is said where they call it (path_tracer.cpp,
// bdpt_tracer.cpp); docs/scene-format.md has the user's view.
#include <cstdint>
#include <optional>
#include <vector>

#include "integrator/path_tracer.h"
#include "pathspace/vertex.h"
#include "sampling/sampler.h"
#include "scene/scene.h"

namespace omega {

// At most this many mirrors take part (the largest by area); any others stay ordinary S
// surfaces. Each costs a light or lens sample and two rays per connection.
constexpr int kMaxPlanarMirrors = 4;
static_assert(kMaxPlanarMirrors <= int(dims::kMirrorSlots), "each mirror needs its own sampler dimensions");

// A shape that is a perfect planar mirror: a triangle mesh whose faces all lie in one plane with
// its normal (flat shading), made of a smooth conductor (delta reflection only), neither masked
// nor bump mapped.
struct PlanarMirror {
    uint32_t shape = 0;
    Vec3 n;       // unit, the faces' normal
    float d = 0;  // the plane: dot(n, p) = d
    double area = 0;

    float side(const Vec3& p) const { return dot(n, p) - d; }
    Vec3 image(const Vec3& p) const { return p - n * (2.f * side(p)); }
    // Whether a chain from p can reflect here: p clearly off the plane (a point on it, or within
    // rounding of it, has no image apart from itself).
    bool usable_from(const Vec3& p) const;
};

// The scene's planar mirrors, the largest first, at most kMaxPlanarMirrors; and for each shape
// its index in that list or -1. Built once per tracer.
struct PlanarMirrors {
    std::vector<PlanarMirror> list;
    std::vector<int8_t> of_shape;
    bool empty() const { return list.empty(); }
    int index(uint32_t shape) const { return shape < of_shape.size() ? of_shape[shape] : -1; }
};
PlanarMirrors find_planar_mirrors(const Scene& scene);

// Where the segment a -> b crosses the mirror's plane, if a and b lie on opposite sides of it.
std::optional<Vec3> plane_crossing(const PlanarMirror& m, const Vec3& a, const Vec3& b);

// The reflection at the mirror along the chain from `from` towards the point m on its plane:
// traces from -> m and requires the mirror to be the first surface hit. Returns the hit and the
// mirror's reflection weight (its delta lobe's F x specular_reflectance, textures looked up).
struct MirrorBounce {
    SurfaceHit hit;
    Rgb weight;
};
std::optional<MirrorBounce> bounce_off(const Scene& scene, const PlanarMirror& mirror, const SurfaceHit& from,
                                       const Vec3& m, TracerStats& stats);

// Next-event estimation through mirror `mi` from the surface point `x` (shading frame, wo, its
// BSDF): a light sample drawn towards x's image, then the chain x -> m -> light. Returns
// f |cos| R Li / p_light (unweighted) and p_light, the chain's density in solid angle at x
// (selection pmf times the light sampler's density at the image); p_light is 0 for a delta
// light, which only this strategy reaches. Draws 3 dimensions from the sampler.
struct MirrorLightSample {
    Rgb L;
    float pdf_light_sa = 0;
    float pdf_bsdf_sa = 0;  // the BSDF's density of the first direction x -> m (the other strategy)
    bool delta_light = false;
};
std::optional<MirrorLightSample> sample_light_via_mirror(const Scene& scene, const PlanarMirror& mirror,
                                                         const SurfaceHit& x, const Frame& shading, const Vec3& wo_local,
                                                         const Bsdf& bsdf, Sampler& sampler, TracerStats& stats);

// The density, in solid angle at x, with which sample_light_via_mirror picks the light point
// `y_hit` of area light `light` (or the environment direction `d`, unit, towards the sky) reached
// from x through the mirror. For the path tracer's MIS when BSDF sampling found the same chain.
float mirror_light_pdf_sa(const Scene& scene, const PlanarMirror& mirror, const Vec3& x, size_t light,
                          const SurfaceHit& y_hit);
float mirror_environment_pdf_sa(const Scene& scene, const PlanarMirror& mirror, const Vec3& x, size_t light, const Vec3& d);

// Light tracing through mirror `mi`: light vertex light[s-1] joined to the sensor by the chain
// y -> m -> camera, the lens sampled from y's image. A splat like strategy (s, 1). Draws 2
// dimensions from the sampler.
struct MirrorSensorSplat {
    Rgb L;  // times the sensor importance: multiply by the filter weight per pixel
    Vec2 film;
};
std::optional<MirrorSensorSplat> connect_sensor_via_mirror(const Scene& scene, const PlanarMirror& mirror,
                                                           const std::vector<PathVertex>& light, int s, Sampler& sampler,
                                                           TracerStats& stats);

}  // namespace omega
