#pragma once
// The closed set of sensors. Local frame (Mitsuba): looks along +z, +y is up, +x is the image's
// left. Film positions are continuous pixel coordinates with the origin at the top-left.
#include <optional>
#include <variant>

#include "film/filter.h"
#include "math/transform.h"
#include "scene/ray.h"
#include "scene/scene_desc.h"

namespace omega {

struct Rect2i {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    bool contains(Vec2 p) const { return p.x >= float(x0) && p.x < float(x1) && p.y >= float(y0) && p.y < float(y1); }
};

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

// Whether a filter's weights at the pixel centres around any point sum to 1 within 1e-12.
bool filter_sums_to_one(const Filter& f);

struct Sensor {
    std::variant<PerspectiveSensor, ThinLensSensor, OrthographicSensor> model;
    Transform to_world;
    float m[12] = {};  // to_world's top 3x4 rows in float, for the per-sample ray
    // local_point({0, 0, 0}), computed once by from_desc: a pinhole's position, where every
    // perspective connection to the sensor ends (light tracing asked for it per vertex).
    Vec3 local_origin;
    // A point of the camera's local frame in world space, in float through m (rays, lens points).
    Vec3 local_point(const Vec3& p) const {
        return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
    }
    int width = 1, height = 1;
    float near_clip = 0;

    // Filled by from_desc for importance (light tracing, MIS): see sensor_importance.cpp.
    double pixel_area = 1;   // image-plane area of one pixel: at z = 1 (perspective, thin lens) or world units (orthographic)
    double crop_pixels = 1;  // pixels actually rendered
    Rect2i crop;
    // The film's reconstruction filter, built once (crop_coverage runs for every t = 1
    // connection and every MIS table; building a Gaussian per call costs an erf).
    Filter pixel_filter{FilterType::Box, 0.5f};
    float filter_radius = 0.5f;
    // The filter's weights at the pixel centres around any point sum to 1 (within 1e-12; box and
    // tent of the usual radii, not the Gaussian), so crop_coverage is 1 wherever the footprint
    // lies inside the crop, without summing them (it ran for every light-tracing connection).
    bool coverage_one_inside = false;
    // Sum over crop pixels of the filter weight at film position p: the fraction of the camera's
    // sampling density (uniform over the crop) that lands at p. 1 inside, less near the border.
    double crop_coverage(Vec2 p) const;

    static Sensor from_desc(const SensorDesc& d);
    // Camera ray through film position `film` (pixels) using lens sample u_lens; weight is 1
    // because each model is sampled in proportion to its importance.
    Ray generate_ray(Vec2 film, Vec2 u_lens) const;
    // Camera-side densities used by MIS (and by the camera subpath's first vertex): the sensor
    // is treated as sampling its whole crop uniformly, so they do not depend on the pixel.
    // pos: area density of the camera vertex (1 for a pinhole); dir: solid-angle density of the
    // direction (1 for orthographic). Zero outside the crop or behind the camera.
    struct Pdf {
        double pos = 0, dir = 0;
    };
    Pdf pdf_we(const Vec3& p_cam, const Vec3& w) const;

    // A camera vertex seen from `ref` (strategy t = 1): where on the film it lands, and the
    // importance to apply: W_e / pdf of the lens point, per unit film-pixel filter weight.
    struct Connection {
        Vec3 p;          // camera vertex (pinhole, lens point, or the orthographic plane point)
        Vec3 wi;         // unit, from ref towards p
        float dist = 0;  // |p - ref|
        Vec2 film;       // film position in pixels
        double importance = 0;  // multiply by the pixel filter weight f(film - pixel centre)
        bool infinite_dir = false;  // orthographic: wi is fixed, no 1/r^2
    };
    std::optional<Connection> sample_wi(const Vec3& ref, Vec2 u_lens) const;

    // Strategy t = 0 (sensor_lens.cpp): a thin lens of finite aperture is a surface in the scene
    // that light subpaths can hit. Only such a lens is hittable; pinholes and the orthographic
    // sensor are delta in position or direction.
    bool lens_hittable() const;
    // Whether generate_ray and sample_wi read their lens sample: only a lens of finite aperture
    // (a pinhole, a zero aperture and the orthographic sensor give the same ray for any u_lens),
    // so the samplers skip that draw elsewhere.
    bool uses_lens_sample() const { return lens_hittable(); }
    Vec3 lens_normal() const;  // world optical axis: the lens disk's normal, facing the scene
    struct LensHit {
        Vec3 p;          // the point on the lens
        float t = 0;     // ray parameter
        Vec2 film;       // film position in pixels
        double importance = 0;  // W_e per unit filter weight: 1 / (A_lens a cos^4 theta)
    };
    // Where `r` crosses the lens disk before tmax, travelling into the camera (from the front),
    // landing near the crop. The lens does not occlude: the ray goes on.
    std::optional<LensHit> intersect_lens(const Ray& r, float tmax) const;

    // The S/D character of the sensor's position and direction (classification, ch. 8.3.2).
    bool delta_position() const;
    bool delta_direction() const;
};

}  // namespace omega
