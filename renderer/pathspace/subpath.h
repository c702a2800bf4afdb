#pragma once
// Local path sampling (Veach 8.2.2.1): camera and light subpaths by random walks.
#include <vector>

#include "integrator/path_tracer.h"
#include "pathspace/vertex.h"
#include "sampling/sampler.h"
#include "scene/scene.h"

namespace omega {

struct WalkLimits {
    int max_vertices = 8;  // including the endpoint
    int rr_depth = 5;      // vertex count after which Russian roulette may end the walk
    // false: the walk leaves pdf_fwd and pdf_rev 0. For walks no MIS weight reads (the light
    // tracer's, when each path has one strategy), the two densities per vertex were 10% of it.
    bool densities = true;
};

// path[0] is the sensor vertex for `ray` (a camera ray from Sensor::generate_ray, whose
// throughput is 1 by importance sampling). Returns the number of vertices. Vertex j scatters
// with the dimensions dims::camera_walk(j, ...), as the path tracer's bounce j does.
int generate_camera_subpath(const Scene& scene, const Ray& ray, const WalkLimits& lim, Sampler& sampler, TracerStats& stats,
                            std::vector<PathVertex>& path);

// Strategy t = 0: an edge of a light subpath that reaches a lens of finite aperture. The full
// path is the walk's first `s` vertices followed by `lens` (a Sensor vertex whose pdf_fwd is
// the walk's area density there); its contribution is beta * W_e, splatted at `film`.
struct LensCrossing {
    int s = 0;
    PathVertex lens;
    Rgb beta;               // throughput of the walk up to the lens
    Vec2 film;
    double importance = 0;  // W_e per unit filter weight
};

// path[0] is a light vertex chosen by power. Returns the number of vertices (0 if the light
// emitted nothing along the sampled ray). If `lens` is given and the sensor's lens can be hit,
// every edge that crosses it is appended there (the walk itself goes on unchanged).
int generate_light_subpath(const Scene& scene, const WalkLimits& lim, Sampler& sampler, TracerStats& stats,
                           std::vector<PathVertex>& path, std::vector<LensCrossing>* lens = nullptr);

// The sensor vertex at world point p (camera subpaths, t = 1 and t = 0): a thin lens of finite
// aperture gets its optical axis as normal, so densities towards it are per unit lens area.
PathVertex sensor_vertex(const Scene& scene, const Vec3& p);

// Area density at `to` of a direction sampled at `from` with solid-angle density pdf_sa
// (eq. 8.10); vertices at infinity keep the solid-angle density.
double to_area_density(const PathVertex& from, double pdf_sa, const PathVertex& to);

// Unit direction from a to b (vertices at infinity by their direction of travel).
Vec3 direction(const PathVertex& a, const PathVertex& b);
// Density with which the sensor at `cam` generates `next` (camera-side MIS density).
double sensor_density_at(const Scene& scene, const PathVertex& cam, const PathVertex& next);
// Density with which the light endpoint v0 (finite or at infinity) emits towards `next`.
double emission_density_at(const Scene& scene, const PathVertex& v0, const PathVertex& next);

// f at a surface vertex towards world direction wi, with the previous vertex of its own
// subpath on the wo side. In Importance mode the shading-normal correction (Veach 5.3) applies.
Rgb vertex_f(const PathVertex& v, const Vec3& wi, TransportMode mode);
// A vertex's wo and a connection direction w in its shading frame: a connection needs them for
// f and for both densities at the vertex, and to_local was a tenth of BDPT's instructions.
struct VertexLocal {
    Vec3 wo, w;
};
// The same as vertex_f(v, wi, mode), with l = {to_local(v.wo), to_local(wi)} already at hand.
Rgb vertex_f(const PathVertex& v, const Vec3& wi, const VertexLocal& l, TransportMode mode);
// Solid-angle density at surface vertex v of sampling direction `to` when the walk arrived
// from direction `from` (both unit world directions pointing away from v).
double vertex_pdf_sa(const PathVertex& v, const Vec3& from, const Vec3& to);

}  // namespace omega
