#pragma once
// BDPT's MIS weights without a density table per connection (Veach's recurrence, as SmallVCM's
// dVC and Tungsten keep it on their vertices).
//
// mis_weight() walks the whole table p_light/p_sensor (mis.h) outwards from strategy s. Of that
// table, a connection (s, t) computes only the densities at the two vertices on each side of its
// edge (EdgeDensities); everything further out is the subpaths' own pdf_fwd/pdf_rev and delta
// flags, the same for every connection of the sample. So the power-heuristic sum beyond those
// vertices is summed once per subpath, from the endpoint inwards:
//   light side   G[m] = possible(m) + (pS[m-1] / pL[m-1])^2 G[m-1],   G[0] = light hittable,
//   camera side  H[q] = possible(n - q) + (pL / pS at camera vertex q-1)^2 H[q-1],
//                H[0] = lens hittable,
// and a connection adds its own two ratios on each side (mis_weight_prefixed). The result is
// mis_weight() to rounding (mis_test.cpp compares the two on every connection it samples).
//
// Only for bdpt's strategy set without the planar-mirror connector and for paths of 3 or more
// vertices; everything else keeps the table (connect() decides).
#include <vector>

#include "pathspace/subpath.h"
#include "pathspace/vertex.h"
#include "sensor/sensor.h"

namespace omega {

class Scene;

// The densities a connection (s >= 1, t >= 1) computes across its edge a = v_{s-1} -- b = v_s;
// the table (full_path_pdfs_into) and the prefixed weight both take them from here.
struct EdgeDensities {
    double sensor_a = 0;   // p_sensor[s-1]: b (or the sensor, t = 1) generating a
    double sensor_a2 = 0;  // p_sensor[s-2]: a generating its predecessor, arrived from b (s >= 2)
    double light_b = 0;    // p_light[s]: a (or the light, s = 1) generating b
    double light_b2 = 0;   // p_light[s+1]: b generating its successor, arrived from a (t >= 2)
    bool a_delta = false, b_delta = false;  // delta as the connection scatters (eval's lobes only)
};
// a2 = v_{s-2} (null for s = 1), b2 = v_{s+1} (null for t = 1). la / lb, when given, are a's and
// b's VertexLocal for the edge (w = direction(a, b) at a, its opposite at b): the same numbers.
// b_we, when given (t = 1, a sensor with directions), is the sensor's pdf_we(b, direction(b, a)),
// which the connection computed already: -wi of sample_wi is that direction, bit for bit.
EdgeDensities edge_densities(const Scene& scene, const PathVertex& a, const PathVertex* a2, const PathVertex& b,
                             const PathVertex* b2, int s, int t, const VertexLocal* la = nullptr,
                             const VertexLocal* lb = nullptr, const Sensor::Pdf* b_we = nullptr);

// Per thread; the BDPT tracer prepares it after each sample's walks and resets it after its
// connections. connect() uses it only when it was prepared for the very subpaths it is given.
struct MisPrefixes {
    const std::vector<PathVertex>* light = nullptr;
    const std::vector<PathVertex>* camera = nullptr;
    size_t n_light = 0, n_camera = 0;
    std::vector<double> light_sum;   // G[m]
    std::vector<double> camera_sum;  // H[q]
    double light_origin = 0;         // p_light[0] of light[0] (light_endpoint_density)
    bool light_hittable = false;     // light[0]'s light (s = 0 could make the path)
    bool sensor_hittable = false;    // a lens of finite aperture (t = 0 could)
    bool ready = false;

    void prepare(const Scene& scene, const std::vector<PathVertex>& light, const std::vector<PathVertex>& camera);
    void reset() { ready = false; }
    bool covers(const std::vector<PathVertex>& l, const std::vector<PathVertex>& c) const {
        return ready && light == &l && camera == &c && n_light == l.size() && n_camera == c.size();
    }
};

// Power-heuristic weight of strategy (s, t), s + t >= 3, for bdpt without the connector.
// `e` is the connection's EdgeDensities (unused for s = 0); sampled_light / sampled_sensor stand
// in for light[0] (s = 1) and camera[0] (t = 1) as in connect(). Negative when not finite.
double mis_weight_prefixed(const Scene& scene, const MisPrefixes& p, int s, int t, const EdgeDensities& e,
                           const PathVertex* sampled_light, const PathVertex* sampled_sensor);

}  // namespace omega
