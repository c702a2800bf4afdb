#include "sensor/sensor.h"

#include <cmath>

#include "sampling/warp.h"

namespace omega {

namespace {

// Image-plane extents at z = 1 from the field of view and the axis it is measured along.
void tangents(const SensorDesc& d, float& tx, float& ty) {
    float aspect = float(d.film.width) / float(d.film.height);
    float t = std::tan(d.fov * kPi / 360.f);
    if (d.fov_axis == 'y') {
        ty = t;
        tx = t * aspect;
    } else {
        tx = t;
        ty = t / aspect;
    }
}

// Film position -> point on the local image plane (z = 1 for perspective). +x is the image's left.
inline Vec2 film_to_plane(Vec2 film, int w, int h, float ex, float ey) {
    return {(1.f - 2.f * film.x / float(w)) * ex, (1.f - 2.f * film.y / float(h)) * ey};
}

}  // namespace

Sensor Sensor::from_desc(const SensorDesc& d) {
    Sensor s;
    s.to_world = *Transform::make(d.to_world);  // the parser rejects singular matrices
    s.width = d.film.width;
    s.height = d.film.height;
    s.near_clip = d.near_clip;
    float tx, ty;
    tangents(d, tx, ty);
    switch (d.type) {
        case SensorType::Perspective: s.model = PerspectiveSensor{tx, ty}; break;
        case SensorType::ThinLens: s.model = ThinLensSensor{tx, ty, d.aperture_radius, d.focus_distance}; break;
        case SensorType::Orthographic: {
            float aspect = float(d.film.width) / float(d.film.height);
            s.model = OrthographicSensor{1.f, 1.f / aspect};
            break;
        }
    }
    return s;
}

Ray Sensor::generate_ray(Vec2 film, Vec2 u_lens) const {
    Vec3d o_local, d_local;
    if (auto* p = std::get_if<PerspectiveSensor>(&model)) {
        Vec2 q = film_to_plane(film, width, height, p->tan_half_x, p->tan_half_y);
        o_local = {0, 0, 0};
        d_local = {q.x, q.y, 1.0};
    } else if (auto* tl = std::get_if<ThinLensSensor>(&model)) {
        Vec2 q = film_to_plane(film, width, height, tl->tan_half_x, tl->tan_half_y);
        Vec2 lens = square_to_uniform_disk_concentric(u_lens);
        Vec3d focus{double(q.x) * tl->focus_distance, double(q.y) * tl->focus_distance, tl->focus_distance};
        o_local = {double(lens.x) * tl->aperture_radius, double(lens.y) * tl->aperture_radius, 0};
        d_local = focus - o_local;
    } else {
        auto& o = std::get<OrthographicSensor>(model);
        Vec2 q = film_to_plane(film, width, height, o.half_x, o.half_y);
        o_local = {q.x, q.y, 0};
        d_local = {0, 0, 1};
    }
    Vec3d local_dir = normalize(d_local);
    Vec3d o = to_world.point(o_local);
    Vec3d d = normalize(to_world.vector(d_local));
    Ray r;
    // near_clip is a distance along the optical axis.
    double t0 = near_clip > 0 ? near_clip / local_dir.z : 0.0;
    r.o = Vec3(o + d * t0);
    r.d = Vec3(d);
    return r;
}

bool Sensor::delta_position() const { return std::holds_alternative<PerspectiveSensor>(model); }
bool Sensor::delta_direction() const { return std::holds_alternative<OrthographicSensor>(model); }

}  // namespace omega
