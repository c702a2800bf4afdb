#pragma once
// One MIS routine for every integrator (path, light, bdpt): the power heuristic over the
// strategies (s, t) that could have produced a full path, restricted to the strategies the
// integrator uses. Ratios accumulate in double.
//
// A full path has vertices v_0 (on a light) ... v_k (on the sensor), k edges. For each vertex:
//   p_light[i]  = density of generating v_i from the light side (area measure; solid angle for
//                 a vertex at infinity; 1 through a delta event),
//   p_sensor[i] = the same from the sensor side.
// Strategy s uses light vertices v_0..v_{s-1} and sensor vertices v_s..v_k (t = k + 1 - s):
//   p_s = prod_{i<s} p_light[i] * prod_{i>=s} p_sensor[i],  so  p_{s+1} / p_s = p_light[s] / p_sensor[s].
#include <cstdint>
#include <vector>

#include "scene/scene_desc.h"

namespace omega {

struct PlanarMirrors;  // pathspace/mirror_connector.h
struct PathVertex;     // pathspace/vertex.h

struct FullPathPdfs {
    std::vector<double> p_light, p_sensor;
    std::vector<uint8_t> delta;  // v_i is S: no strategy can connect an edge at it
    // The planar-mirror connector (pathspace/mirror_connector.h) through v_j, a delta vertex on a
    // connector mirror between two non-delta ones: connector[j] = J_j > 0, the Jacobian that puts
    // the connector's density, prod_{i<j} p_light[i] prod_{i>j} p_sensor[i] / J_j, in the units
    // of the others (mirror_connector_factors). 0 elsewhere; empty when the path has no such
    // vertex (the common case costs nothing).
    std::vector<double> connector;
    std::vector<const PathVertex*> vertices;  // scratch for full_path_pdfs_into: no allocation per connection
    bool light_hittable = true;  // s = 0: the light can be hit by a sensor subpath (not delta in position or direction)
    bool light_at_infinity = false;  // v_0 is at infinity: s = 1, t = 1 cannot connect it to the sensor
    bool sensor_hittable = false;    // t = 0: light subpaths can hit the sensor (a lens of finite aperture)
    int k() const { return int(p_light.size()) - 1; }
};

// Which (s, t) strategies an integrator uses. Strategies outside the set get no weight.
struct StrategySet {
    IntegratorType type = IntegratorType::Bdpt;
    // The planar-mirror connector through v_j is the strategy with s = j light vertices and
    // t = k - j sensor vertices. The path tracer uses it for s = 1 (t >= 2), the light tracer for t = 1
    // (not with a hittable lens, whose t = 0 strategy it would have to weigh), bdpt for all.
    const PlanarMirrors* mirrors = nullptr;  // null: no connector (the scene has no planar mirror)
    bool lens_hittable = false;
    bool allows_connector(int s, int t) const {
        if (!mirrors || s < 1 || t < 1) return false;
        switch (type) {
            case IntegratorType::Path: return s == 1 && t >= 2;
            case IntegratorType::Light: return t == 1 && !lens_hittable;
            case IntegratorType::Bdpt: return true;
        }
        return false;
    }
    // Only one strategy can make each path (the light tracer's t = 1, no connector), so every
    // weight is exactly 1 (the MIS sum holds that strategy alone) and no density table is needed.
    bool single_strategy() const { return type == IntegratorType::Light && !mirrors; }
    bool allows(int s, int t) const {
        switch (type) {
            case IntegratorType::Path: return s <= 1;
            case IntegratorType::Light: return t == 1;
            case IntegratorType::Bdpt: return true;
        }
        return false;
    }
};

// Can strategy s produce this path at all (ignoring the integrator)? t = 0 only when the lens
// has a finite aperture that light subpaths can hit.
bool strategy_possible(const FullPathPdfs& path, int s);

// Power-heuristic weight of strategy s. Returns a negative value if the computation is not
// finite (an error the caller counts, never a silent NaN).
double mis_weight(const FullPathPdfs& path, int s, const StrategySet& set);
// The same for the connector through v_j (path.connector[j] > 0).
double mis_weight_connector(const FullPathPdfs& path, int j, const StrategySet& set);

}  // namespace omega
