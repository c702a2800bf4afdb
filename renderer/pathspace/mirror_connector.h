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
// The path tracer uses it for next-event estimation (path_tracer.cpp, weighed against BSDF
// sampling in solid angle); the light tracer and bdpt as a strategy in the MIS routine
// (StrategySet::allows_connector, mis_weight_connector). docs/scene-format.md has the user's view.
#include <cstdint>
#include <optional>
#include <vector>

#include "integrator/path_tracer.h"
#include "pathspace/connect.h"
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

// Next-event estimation through `mirror` from the surface point `x` (shading frame, wo, its
// BSDF): a light sample drawn towards x's image, then the chain x -> m -> light. L is
// f |cos| R Li / p_light (unweighted); p_light is the chain's density in solid angle at x
// (selection pmf times the light sampler's density at the image), pdf_bsdf_sa the BSDF's density
// of the same first direction (the other strategy); delta_light: only this strategy reaches it.
// Also the mirror point and the light endpoint as a path vertex (as strategy s = 1 records it).
// Draws 3 dimensions from the sampler.
struct LightChain {
    Rgb L;
    float pdf_light_sa = 0, pdf_bsdf_sa = 0;
    bool delta_light = false;
    SurfaceHit mirror;
    PathVertex light_vertex;
};
std::optional<LightChain> sample_light_chain(const Scene& scene, const PlanarMirror& mirror, const SurfaceHit& x,
                                             const Frame& shading, const Vec3& wo_local, const Bsdf& bsdf, Sampler& sampler,
                                             TracerStats& stats);

// The density, in solid angle at x, with which sample_light_chain picks the light point
// `y_hit` of area light `light` (or the environment direction `d`, unit, towards the sky) reached
// from x through the mirror. For the path tracer's MIS when BSDF sampling found the same chain.
float mirror_light_pdf_sa(const Scene& scene, const PlanarMirror& mirror, const Vec3& x, size_t light,
                          const SurfaceHit& y_hit);
float mirror_environment_pdf_sa(const Scene& scene, const PlanarMirror& mirror, const Vec3& x, size_t light, const Vec3& d);

// The table entries of the connector (FullPathPdfs::connector) for the full path v: for every
// delta vertex v_j on a connector mirror between two vertices that are not delta, the Jacobian
// J_j that puts the connector's density in the units of the other strategies. The connector
// samples v_{j-1} and v_{j+1} (area measure each) and leaves v_j to the reflection; the
// sensor-side strategies sample v_{j+1} and v_j (area) and leave v_{j-1} to the delta, so the
// two differ by J = dA(v_j)/dA(v_{j-1}) at fixed v_{j+1}: rays from the image of v_{j+1} through
// the mirror, J = |cos v_{j-1}| d1^2 / (|cos m| (d0 + d1)^2) with d0 = |v_{j-1} - m|,
// d1 = |m - v_{j+1}|. Where v_{j-1} has no area measure (a point light, a light at infinity)
// the light side's J = dA(v_j)/dA(v_{j+1}) stands in. MIS weights sum to 1 whatever J is; J only
// makes them good.
void mirror_connector_factors(const PlanarMirrors& mirrors, const std::vector<const PathVertex*>& v, FullPathPdfs& fp);

// Strategy (s, t) through mirror `mi` (s >= 1 light vertices, t >= 1 sensor vertices, k = s + t
// edges with the mirror vertex between): s = 1 samples the light from the image of camera[t-1]
// (3 dimensions, dims::mirror_light(t - 1, mi)); t = 1 samples the lens from the image of
// light[s-1] (2 dimensions, dims::mirror_sensor(s, mi)), a splat; otherwise the reflection
// point is found from the two vertices. The weight is the connector's MIS weight in `set`.
// Tests may ask for the full path (light end first, the mirror vertex at index s) and its table.
std::optional<Connection> connect_via_mirror(const Scene& scene, int mi, const std::vector<PathVertex>& light,
                                             const std::vector<PathVertex>& camera, int s, int t, const StrategySet& set,
                                             Sampler& sampler, TracerStats& stats, ConnectStats& cstats,
                                             std::vector<PathVertex>* full_path = nullptr, FullPathPdfs* pdfs = nullptr);

}  // namespace omega
