// The thin lens as a hittable surface, for strategy t = 0 (Veach 10.2: light subpaths that
// reach the lens). The importance per unit area and projected solid angle follows from the same
// film parametrisation as sensor_importance.cpp: a pixel's measurement is
//   I_j = (1 / A_lens) int_lens int_film f(p - p_j) L dp dA,  dp = dw / (a cos^3 theta),
// so W_e = f / (A_lens a cos^4 theta) once L is integrated against cos theta dw.
#include <cmath>

#include "sensor/film_plane.h"
#include "sensor/sensor.h"

namespace omega {

bool Sensor::lens_hittable() const {
    auto* tl = std::get_if<ThinLensSensor>(&model);
    return tl && tl->aperture_radius > 0;
}

Vec3 Sensor::lens_normal() const { return Vec3(normalize(to_world.fwd.vector(Vec3d(0, 0, 1)))); }

std::optional<Sensor::LensHit> Sensor::intersect_lens(const Ray& r, float tmax) const {
    auto* tl = std::get_if<ThinLensSensor>(&model);
    if (!tl || !(tl->aperture_radius > 0)) return std::nullopt;
    // In the camera's local frame; an affine map keeps the ray parameter.
    Vec3d o = to_world.inv.point(Vec3d(r.o)), d = to_world.inv.vector(Vec3d(r.d));
    if (!(d.z < 0) || !(o.z > 0)) return std::nullopt;  // only light travelling into the camera
    double t = -o.z / d.z;
    if (!(t > 0) || !(t < double(tmax))) return std::nullopt;
    double x = o.x + t * d.x, y = o.y + t * d.y;
    const double R = tl->aperture_radius;
    if (x * x + y * y > R * R) return std::nullopt;
    // The direction from the lens point back to the scene crosses the focus plane at the point
    // that a camera ray through this film position would aim at (Sensor::generate_ray).
    Vec3d out = -d;
    double tf = double(tl->focus_distance) / out.z;
    double qx = (x + out.x * tf) / tl->focus_distance, qy = (y + out.y * tf) / tl->focus_distance;
    LensHit h;
    h.film = film_plane::to_film(float(qx), float(qy), tl->tan_half_x, tl->tan_half_y, width, height);
    if (!film_plane::near_crop(crop, h.film, filter_radius)) return std::nullopt;
    h.p = Vec3(to_world.fwd.point(Vec3d(x, y, 0)));
    h.t = float(t);
    double cos_t = out.z / length(out);
    double c2 = cos_t * cos_t;
    h.importance = 1.0 / (kPiD * R * R * pixel_area * c2 * c2);
    return h;
}

}  // namespace omega
