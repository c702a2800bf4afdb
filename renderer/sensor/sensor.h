#pragma once
// The closed set of sensors. Local frame (Mitsuba): looks along +z, +y is up, +x is the image's
// left. Film positions are continuous pixel coordinates with the origin at the top-left.
#include <variant>

#include "math/transform.h"
#include "scene/ray.h"
#include "scene/scene_desc.h"

namespace omega {

struct PerspectiveSensor {
    float tan_half_x = 1, tan_half_y = 1;  // image plane at z = 1 spans [-tan, tan]
};
struct ThinLensSensor {
    float tan_half_x = 1, tan_half_y = 1;
    float aperture_radius = 0, focus_distance = 1;
};
struct OrthographicSensor {
    float half_x = 1, half_y = 1;  // local extent before to_world
};

struct Sensor {
    std::variant<PerspectiveSensor, ThinLensSensor, OrthographicSensor> model;
    Transform to_world;
    float m[12] = {};  // to_world's top 3x4 rows in float, for the per-sample ray
    int width = 1, height = 1;
    float near_clip = 0;

    static Sensor from_desc(const SensorDesc& d);
    // Camera ray through film position `film` (pixels) using lens sample u_lens; weight is 1
    // because each model is sampled in proportion to its importance.
    Ray generate_ray(Vec2 film, Vec2 u_lens) const;
    // The S/D character of the sensor's position and direction (classification, ch. 8.3.2).
    bool delta_position() const;
    bool delta_direction() const;
};

}  // namespace omega
