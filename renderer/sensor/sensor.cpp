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
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) s.m[r * 4 + c] = float(d.to_world(r, c));
    s.local_origin = s.local_point({0.f, 0.f, 0.f});
    s.width = d.film.width;
    s.height = d.film.height;
    s.near_clip = d.near_clip;
    float tx, ty;
    tangents(d, tx, ty);
    const FilmDesc& f = d.film;
    s.crop = f.has_crop ? Rect2i{f.crop[0], f.crop[1], f.crop[2], f.crop[3]} : Rect2i{0, 0, f.width, f.height};
    s.crop_pixels = double(s.crop.x1 - s.crop.x0) * double(s.crop.y1 - s.crop.y0);
    s.pixel_filter = Filter(f.filter, f.filter_radius, f.gaussian_stddev);
    s.filter_radius = f.filter_radius;
    s.coverage_one_inside = filter_sums_to_one(s.pixel_filter);
    if (d.type == SensorType::Orthographic) {
        // World extent of the plane: to_world's x and y axis lengths scale the local [-1,1] x [-1/aspect, 1/aspect].
        double sx = length(d.to_world.vector({1, 0, 0})), sy = length(d.to_world.vector({0, 1, 0}));
        double aspect = double(f.width) / double(f.height);
        s.pixel_area = (2.0 * sx / f.width) * (2.0 * sy / aspect / f.height);
    } else {
        s.pixel_area = (2.0 * tx / f.width) * (2.0 * ty / f.height);
    }
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
    Vec3 o_local, d_local;
    if (auto* p = std::get_if<PerspectiveSensor>(&model)) {
        Vec2 q = film_to_plane(film, width, height, p->tan_half_x, p->tan_half_y);
        d_local = {q.x, q.y, 1.f};
    } else if (auto* tl = std::get_if<ThinLensSensor>(&model)) {
        Vec2 q = film_to_plane(film, width, height, tl->tan_half_x, tl->tan_half_y);
        Vec2 lens = square_to_uniform_disk_concentric(u_lens);
        Vec3 focus{q.x * tl->focus_distance, q.y * tl->focus_distance, tl->focus_distance};
        o_local = {lens.x * tl->aperture_radius, lens.y * tl->aperture_radius, 0.f};
        d_local = focus - o_local;
    } else {
        auto& o = std::get<OrthographicSensor>(model);
        Vec2 q = film_to_plane(film, width, height, o.half_x, o.half_y);
        o_local = {q.x, q.y, 0.f};
        d_local = {0.f, 0.f, 1.f};
    }
    // A pinhole's origin is local_origin, the same bits as local_point of zero.
    Vec3 o = std::holds_alternative<PerspectiveSensor>(model) ? local_origin : local_point(o_local);
    Vec3 d = normalize(Vec3{m[0] * d_local.x + m[1] * d_local.y + m[2] * d_local.z,
                            m[4] * d_local.x + m[5] * d_local.y + m[6] * d_local.z,
                            m[8] * d_local.x + m[9] * d_local.y + m[10] * d_local.z});
    Ray r;
    r.o = o;
    r.d = d;
    if (near_clip > 0) {
        // near_clip is a distance along the optical axis (local z).
        r.o += d * (near_clip * length(d_local) / d_local.z);
    }
    return r;
}

bool Sensor::delta_position() const { return std::holds_alternative<PerspectiveSensor>(model); }
bool Sensor::delta_direction() const { return std::holds_alternative<OrthographicSensor>(model); }

}  // namespace omega
