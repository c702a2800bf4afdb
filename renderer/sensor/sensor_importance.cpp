// Importance W_e of each sensor and the camera-side densities, for light tracing (t = 1) and MIS.
//
// With filter importance sampling, pixel j measures I_j = int f(p - p_j) L(ray(p)) dp (p in
// pixels). For a perspective or thin-lens camera, dp = dw / (a cos^3 theta) where a is the area of
// a pixel on the image plane at z = 1 and theta the angle to the optical axis, so the importance
// per solid angle is f / (a cos^3 theta) (the lens adds 1 / lens area, cancelled by sampling the
// lens uniformly). For the orthographic camera, dp = dA / a_world on the sensor plane.
#include <cmath>

#include "film/filter.h"
#include "sampling/warp.h"
#include "sensor/film_plane.h"
#include "sensor/sensor.h"

namespace omega {

bool filter_sums_to_one(const Filter& f) {
    const double r = f.radius();
    for (int i = 0; i < 64; ++i) {
        const double x = (i + 0.5) / 64.0;  // offset from a pixel centre
        double sum = 0;
        for (int c = -int(std::ceil(r)) - 1; c <= int(std::ceil(r)) + 1; ++c) sum += f.pdf_1d(x - c);
        if (std::abs(sum - 1.0) > 1e-12) return false;
    }
    return true;
}

double Sensor::crop_coverage(Vec2 p) const {
    const Filter& f = pixel_filter;
    // Inside the crop by more than the footprint: every weight is a crop pixel's.
    const double margin = double(filter_radius) + 1.0;
    if (coverage_one_inside && p.x >= crop.x0 + margin && p.x <= crop.x1 - margin && p.y >= crop.y0 + margin &&
        p.y <= crop.y1 - margin)
        return 1.0;
    auto axis = [&](double x, int lo, int hi) {
        const auto [a, b] = filter_span(x, filter_radius, lo, hi);
        double sum = 0;
        for (int i = a; i <= b; ++i) sum += f.pdf_1d(x - (i + 0.5));
        return sum;
    };
    return axis(p.x, crop.x0, crop.x1) * axis(p.y, crop.y0, crop.y1);
}

Sensor::Pdf Sensor::pdf_we(const Vec3& p_cam, const Vec3& w) const {
    Pdf pdf;
    Vec3 wl = Vec3(normalize(to_world.inv.vector(Vec3d(w))));
    if (wl.z <= 0) return pdf;
    const double a_total = pixel_area * crop_pixels;
    if (auto* o = std::get_if<OrthographicSensor>(&model)) {
        if (wl.z < 1.f - 1e-5f) return pdf;
        Vec3 pl = Vec3(to_world.inv.point(Vec3d(p_cam)));
        double cov = crop_coverage(film_plane::to_film(pl.x, pl.y, o->half_x, o->half_y, width, height));
        if (!(cov > 0)) return pdf;
        pdf.pos = cov / a_total;
        pdf.dir = 1.0;
        return pdf;
    }
    float ex, ey;
    if (auto* p = std::get_if<PerspectiveSensor>(&model)) {
        ex = p->tan_half_x;
        ey = p->tan_half_y;
        pdf.pos = 1.0;
    } else {
        auto& tl = std::get<ThinLensSensor>(model);
        ex = tl.tan_half_x;
        ey = tl.tan_half_y;
        pdf.pos = tl.aperture_radius > 0 ? 1.0 / (kPiD * double(tl.aperture_radius) * tl.aperture_radius) : 1.0;
    }
    // Where the direction crosses the image plane (through the focus plane for a lens point).
    Vec2 q{wl.x / wl.z, wl.y / wl.z};
    if (auto* tl = std::get_if<ThinLensSensor>(&model)) {
        Vec3 lens = Vec3(to_world.inv.point(Vec3d(p_cam)));
        float t = tl->focus_distance / wl.z;
        q = {(lens.x + wl.x * t) / tl->focus_distance, (lens.y + wl.y * t) / tl->focus_distance};
    }
    double cov = crop_coverage(film_plane::to_film(q.x, q.y, ex, ey, width, height));
    if (!(cov > 0)) {
        pdf.pos = 0;
        return pdf;
    }
    double c = wl.z;
    pdf.dir = cov / (a_total * c * c * c);
    return pdf;
}

std::optional<Sensor::Connection> Sensor::sample_wi(const Vec3& ref, Vec2 u_lens) const {
    Connection c;
    Vec3 rl = Vec3(to_world.inv.point(Vec3d(ref)));  // ref in the camera's local frame
    if (auto* o = std::get_if<OrthographicSensor>(&model)) {
        if (rl.z <= 0) return std::nullopt;
        c.film = film_plane::to_film(rl.x, rl.y, o->half_x, o->half_y, width, height);
        if (!film_plane::near_crop(crop, c.film, filter_radius)) return std::nullopt;
        c.p = local_point({rl.x, rl.y, 0.f});
        Vec3 d = c.p - ref;
        c.dist = length(d);
        if (!(c.dist > 0)) return std::nullopt;
        c.wi = d / c.dist;
        c.importance = 1.0 / pixel_area;
        c.infinite_dir = true;
        return c;
    }
    float ex, ey;
    Vec3 lens_local{0, 0, 0};
    float focus = 1.f;
    bool pinhole = false;
    if (auto* p = std::get_if<PerspectiveSensor>(&model)) {
        pinhole = true;
        ex = p->tan_half_x;
        ey = p->tan_half_y;
    } else {
        auto& tl = std::get<ThinLensSensor>(model);
        ex = tl.tan_half_x;
        ey = tl.tan_half_y;
        Vec2 l = square_to_uniform_disk_concentric(u_lens);
        lens_local = {l.x * tl.aperture_radius, l.y * tl.aperture_radius, 0.f};
        focus = tl.focus_distance;
    }
    Vec3 dl = rl - lens_local;  // local direction from the lens point to ref
    if (dl.z <= 0) return std::nullopt;
    // The film position is where the ray from the lens point crosses the focus plane, projected
    // through the pinhole (for a pinhole, focus = 1 and the lens point is the origin).
    float t = focus / dl.z;
    // A pinhole's lens point is 0 and its focus 1: adding the one and dividing by the other change
    // no bit, and the two divisions lay on the chain that decides near_crop's branch (light
    // tracing's most mispredicted: most light vertices fall outside the view).
    Vec2 q = pinhole ? Vec2{dl.x * t, dl.y * t}
                     : Vec2{(lens_local.x + dl.x * t) / focus, (lens_local.y + dl.y * t) / focus};
    c.film = film_plane::to_film(q.x, q.y, ex, ey, width, height);
    if (!film_plane::near_crop(crop, c.film, filter_radius)) return std::nullopt;
    c.p = pinhole ? local_origin : local_point(lens_local);  // the same bits: lens_local is 0
    Vec3 d = c.p - ref;
    c.dist = length(d);
    if (!(c.dist > 0)) return std::nullopt;
    c.wi = d / c.dist;
    double cos_t = dl.z / length(dl);
    c.importance = 1.0 / (pixel_area * cos_t * cos_t * cos_t);
    return c;
}

}  // namespace omega
