#pragma once
// Full-path regular expressions (Veach 8.3.2) for a scene: each emitter is L(S|D)(S|D), the
// sensor (S|D)(S|D)E, each BSDF component S or D. From them the renderer decides which (s, t)
// strategies can never contribute (and skips them) and which path classes cannot be sampled at
// all (Theorem 8.3: no DD) or not by the chosen integrator, and says so in plain words.
#include <string>
#include <vector>

#include "scene/scene.h"

namespace omega {

// One emitter or sensor class: two letters, each 'S' or 'D'.
struct EndpointClass {
    char position = 'D', direction = 'D';
};

// Emitter: position then direction (LXY). Sensor: direction then position (YXE).
EndpointClass classify_light(const Light& light);
EndpointClass classify_sensor(const Sensor& sensor);

// A path class: an emitter, a sequence of surface scattering symbols, a sensor. Surface symbols
// are S, D, and M: an S vertex on one of the planar mirrors the connector reflects in
// (pathspace/mirror_connector.h). M is S to Theorem 8.3 and in every printed expression.
struct PathClass {
    EndpointClass light;
    std::string surfaces;  // e.g. "SDS"
    EndpointClass sensor;
    std::string regex() const;  // "L S D S D S E"
};

// Theorem 8.3: some local strategy samples the path iff "DD" occurs in its full-path string,
// endpoint letters included (LDD: a sensor subpath hits the light; DDE: a light subpath hits
// the lens).
bool locally_sampleable(const PathClass& c);

// Whether this renderer's strategies in `set` can sample the class. Beyond Theorem 8.3 the
// renderer has connectors of its own: next-event estimation reaches directional lights by
// projection, light tracing reaches the orthographic sensor by projection, and the planar-mirror
// connector joins D to a light (path tracer) or a light-side D or light endpoint to a pinhole or
// orthographic sensor (light tracer) through one M vertex.
bool sampleable_by(const PathClass& c, IntegratorType integrator);

// What a scene can produce: its emitter classes, sensor class and surface symbols.
struct SceneClasses {
    std::vector<EndpointClass> lights;  // distinct
    std::vector<std::string> light_names;
    EndpointClass sensor;
    std::string sensor_name;
    bool has_diffuse = false, has_specular = false;  // some shape's BSDF has a D / S component (S: not a planar mirror)
    bool has_planar_mirror = false;                  // some shape is a connector mirror (M)
    bool any_light_hittable = false;                 // some light is L D D (s = 0 can contribute)
};
SceneClasses classify_scene(const Scene& scene);

// Plain-words warnings for the classes the scene can produce but cannot be sampled: by any
// local strategy, or by this integrator. At most a few, shortest first.
std::vector<std::string> path_space_warnings(const Scene& scene, IntegratorType integrator);

// Which strategies can contribute in this scene at all; the rest are never evaluated.
struct StrategyPlan {
    bool s0 = true;             // camera subpaths hitting lights
    bool connections = true;    // strategies with s >= 1 that end an edge at a surface (need a D surface);
                                // (s, t) = (1, 1), a light endpoint joined to the sensor, always stays
    bool light_subpaths = true; // walks beyond the light endpoint (s >= 2 or t = 1 need a D surface;
                                // t = 0 needs none)
    bool t0 = false;            // light subpaths hitting the lens (a thin lens of finite aperture)
};
StrategyPlan plan_strategies(const Scene& scene);

}  // namespace omega
