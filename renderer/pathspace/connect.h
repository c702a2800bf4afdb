#pragma once
// Joining a light subpath prefix (s vertices) and a camera subpath prefix (t vertices) into one
// full path with k = s + t - 1 edges: its unweighted contribution f(x)/p(x), and the densities
// every strategy would have had for it (FullPathPdfs) for the MIS weight.
#include <optional>
#include <vector>

#include "pathspace/mis.h"
#include "pathspace/mis_prefix.h"
#include "pathspace/subpath.h"

namespace omega {

struct Connection {
    Rgb L;               // unweighted contribution f/p of the full path
    double weight = 1;   // MIS weight (power heuristic over the integrator's strategies)
    bool splat = false;  // t = 1: lands at `film` instead of the camera subpath's pixel
    Vec2 film;
    double importance = 0;  // t = 1: multiply by the filter weight of each pixel it reaches
};

// Per-thread counters and scratch for connect().
struct ConnectStats {
    uint64_t bad_weights = 0;  // non-finite MIS weights: counted as errors, contribution dropped
    FullPathPdfs table;        // reused: no allocation per connection once warmed up
    std::vector<PathVertex> mirror_camera;  // the planar-mirror connector's camera side with the mirror vertex
    MisPrefixes prefix;  // BDPT: the current sample's subpath sums; connect() uses them when they cover its subpaths
    // The endpoint connect() samples for s = 1 or t = 1, valid during one call. A local
    // std::optional<PathVertex> was zeroed whole (a `rep stos` of 184 bytes) on every call.
    PathVertex sampled;
};

// Strategy (s, t) for the given subpaths. Tests may ask for the full path v_0..v_k (light end
// first, endpoints included) and its densities.
// Strategy (s, t) for the given subpaths (light.size() >= s, camera.size() >= t). Returns nothing
// if the strategy cannot produce a path here (delta vertices, no light hit, occluded...).
std::optional<Connection> connect(const Scene& scene, const std::vector<PathVertex>& light,
                                  const std::vector<PathVertex>& camera, int s, int t, const StrategySet& set,
                                  Sampler& sampler, TracerStats& stats, ConnectStats& cstats,
                                  std::vector<PathVertex>* full_path = nullptr, FullPathPdfs* pdfs = nullptr);

// Strategy t = 0: the light subpath light[0..lc.s) that reached the lens. The contribution is a
// splat, like t = 1 (no shadow ray: the walk's own edge reached the lens unoccluded).
std::optional<Connection> connect_lens(const Scene& scene, const std::vector<PathVertex>& light,
                                       const LensCrossing& lc, const StrategySet& set, ConnectStats& cstats,
                                       FullPathPdfs* pdfs = nullptr);

// Builds the densities of the full path light[0..s) + reverse(camera[0..t)), with sampled_light
// standing in for light[0] (s = 1) and sampled_sensor for camera[0] (t = 1) or for the lens vertex
// ending the light side (t = 0; without it, light[s-1] is the lens) when the connection
// sampled that endpoint afresh.
// Density of a light endpoint v0 from the light side: selection pmf x its position density (area
// measure), or x its direction density for a light at infinity; the pmf alone for a point light.
double light_endpoint_density(const Scene& scene, const PathVertex& v0);
// The light endpoint that next-event estimation sampled (strategy s = 1), as a path vertex.
PathVertex light_sample_vertex(size_t light, const LightSample& ls);

// The full path of strategy (s, t), light first: light[0..s) (the first replaced by
// sampled_light when given), then `mirror` when the planar-mirror connector made it, then
// camera[t-1..0] (camera[0] replaced by sampled_sensor when given). For tests and checks.
void assemble_full_path(const std::vector<PathVertex>& light, const std::vector<PathVertex>& camera, int s, int t,
                        const PathVertex* sampled_light, const PathVertex* sampled_sensor, const PathVertex* mirror,
                        std::vector<PathVertex>& out);

FullPathPdfs full_path_pdfs(const Scene& scene, const std::vector<PathVertex>& light,
                            const std::vector<PathVertex>& camera, int s, int t, const PathVertex* sampled_light,
                            const PathVertex* sampled_sensor, const PlanarMirrors* mirrors = nullptr);
// With `mirrors`, fp.connector is filled for every vertex the planar-mirror connector could
// join across (see mis.h); without, it stays empty.
void full_path_pdfs_into(const Scene& scene, const std::vector<PathVertex>& light,
                         const std::vector<PathVertex>& camera, int s, int t, const PathVertex* sampled_light,
                         const PathVertex* sampled_sensor, FullPathPdfs& fp, const PlanarMirrors* mirrors = nullptr);

}  // namespace omega
