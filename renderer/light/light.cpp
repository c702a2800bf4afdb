#include "light/light.h"

#include <cmath>

#include "math/float_bits.h"
#include "pathspace/measure.h"
#include "sampling/warp.h"
#include "scene/scene.h"
#include "scene/shape_area_sample.h"

namespace omega {

namespace {

// Spot falloff (Mitsuba 3): 1 inside the beam, linear in angle to 0 at the cutoff.
float spot_falloff(const SpotLight& s, const Vec3& w_local) {
    float cos_t = w_local.z;
    if (cos_t <= s.cos_cutoff) return 0.f;
    float angle = std::acos(std::min(cos_t, 1.f));
    if (angle <= s.beam_rad) return 1.f;
    if (s.cutoff_rad <= s.beam_rad) return 1.f;
    return std::clamp((s.cutoff_rad - angle) / (s.cutoff_rad - s.beam_rad), 0.f, 1.f);
}

// Reference points on or inside the sphere sample its area: cone sampling is only valid from
// strictly outside. The relative margin keeps points on the surface (whose computed distance
// may round either way) on the area side; area sampling is unbiased from anywhere.
bool sphere_area_sampling(double dc2, double r) { return dc2 <= r * r * (1.0 + 1e-4); }

struct SpherePoint {
    Vec3 p, n;
    float pdf_sa;
};

// Uniform over the cone of directions the sphere subtends (pbrt-v4's Sphere::Sample), or
// uniform over its area when the reference point is inside.
std::optional<SpherePoint> sample_sphere(const SphereData& s, const Vec3& ref, Vec2 u) {
    Vec3d c = s.center, pr(ref);
    double r = s.radius;
    double dc2 = length_sq(pr - c);
    if (sphere_area_sampling(dc2, r)) {
        Vec3 n = square_to_uniform_sphere(u);
        Vec3d pd = c + Vec3d(n) * r;
        Vec3 p(pd);
        Vec3 d = p - ref;
        float dist2 = length_sq(d);
        if (dist2 == 0) return std::nullopt;
        float cos_l = absdot(n, d / std::sqrt(dist2));
        float pdf_sa = convert_area_to_sa(float(1.0 / (4.0 * kPiD * r * r)), dist2, cos_l);
        if (pdf_sa == 0) return std::nullopt;
        return SpherePoint{p, n, pdf_sa};
    }
    double dc = std::sqrt(dc2);
    float sin_max = float(r / dc);
    float sin2_max = sin_max * sin_max;
    float cos_max = safe_sqrt(1.f - sin2_max);
    float one_minus_cos_max = 1.f - cos_max;
    float cos_t = (cos_max - 1.f) * u.x + 1.f;
    float sin2_t = 1.f - cos_t * cos_t;
    if (sin2_max < 0.00068523f) {  // sin^2(1.5 deg): Taylor forms keep precision for small cones
        sin2_t = sin2_max * u.x;
        cos_t = std::sqrt(1.f - sin2_t);
        one_minus_cos_max = sin2_max / 2.f;
    }
    // Angle alpha at the centre between the axis and the sampled point.
    float cos_a = sin2_t / sin_max + cos_t * safe_sqrt(1.f - sin2_t / sin2_max);
    float sin_a = safe_sqrt(1.f - cos_a * cos_a);
    float phi = u.y * 2.f * kPi;
    Vec3 w{sin_a * std::cos(phi), sin_a * std::sin(phi), cos_a};
    Frame f = Frame::from_normal(Vec3(normalize(c - pr)));
    Vec3 n = f.to_world(-w);
    Vec3d pd = c + Vec3d(n) * r;
    return SpherePoint{Vec3(pd), n, 1.f / (2.f * kPi * one_minus_cos_max)};
}

float sphere_pdf_sa(const SphereData& s, const Vec3& ref, const SurfaceHit& hit) {
    Vec3d c = s.center, pr(ref);
    double r = s.radius;
    double dc2 = length_sq(pr - c);
    if (sphere_area_sampling(dc2, r)) {
        Vec3 d = hit.p - ref;
        float dist2 = length_sq(d);
        return convert_area_to_sa(float(1.0 / (4.0 * kPiD * r * r)), dist2, absdot(hit.ng, d / std::sqrt(dist2)));
    }
    float sin2_max = float(r * r / dc2);
    float cos_max = safe_sqrt(1.f - sin2_max);
    float one_minus_cos_max = sin2_max < 0.00068523f ? sin2_max / 2.f : 1.f - cos_max;
    return 1.f / (2.f * kPi * one_minus_cos_max);
}

}  // namespace

Rgb area_light_le(const AreaLight& light, const SurfaceHit& hit, const Vec3& w) {
    if (light.two_sided || dot(hit.ng, w) > 0) return light.radiance;
    return Rgb(0.f);
}

bool light_faces_away(const Scene& scene, const Light& light, const Vec3& ref) {
    const auto* a = std::get_if<AreaLight>(&light);
    if (!a || a->two_sided) return false;
    const auto& plane = scene.shapes()[a->shape].emitter_plane;
    return plane && behind(*plane, ref);
}

std::optional<LightSample> light_sample_li(const Scene& scene, const Light& light, const Vec3& ref, Vec2 u) {
    if (auto* a = std::get_if<AreaLight>(&light)) {
        const Shape& sh = scene.shapes()[a->shape];
        LightSample ls;
        if (sh.kind == ShapeKind::Sphere) {
            auto sp = sample_sphere(sh.sphere, ref, u);
            if (!sp) return std::nullopt;
            ls.p = sp->p;
            ls.n = sh.flip_normals ? -sp->n : sp->n;
            ls.p_error = abs(ls.p) * gamma_bound(5);
            ls.pdf_sa = sp->pdf_sa;
            Vec3 d = ls.p - ref;
            float dist = length(d);
            if (!(dist > 0)) return std::nullopt;
            ls.wi = d / dist;
        } else {
            const AreaPoint q = sample_shape_area(sh, u);
            ls.p = q.p;
            ls.p_error = q.p_error;
            ls.n = sh.face_normals[q.tri];
            // One square root for the direction and the density's cosine.
            Vec3 d = ls.p - ref;
            float dist2 = length_sq(d);
            if (!(dist2 > 0)) return std::nullopt;
            ls.wi = d / std::sqrt(dist2);
            ls.pdf_sa = convert_area_to_sa(sh.inv_area, dist2, absdot(ls.n, ls.wi));
            if (ls.pdf_sa == 0) return std::nullopt;
        }
        if (!(a->two_sided || dot(ls.n, -ls.wi) > 0)) return std::nullopt;
        ls.Li = a->radiance;
        return ls;
    }
    if (auto* p = std::get_if<PointLight>(&light)) {
        Vec3 d = p->position - ref;
        float dist2 = length_sq(d);
        if (!(dist2 > 0)) return std::nullopt;
        LightSample ls;
        ls.p = p->position;
        ls.wi = d / std::sqrt(dist2);
        ls.Li = p->intensity / dist2;
        ls.pdf_sa = 1.f;
        ls.delta = true;
        return ls;
    }
    if (auto* s = std::get_if<SpotLight>(&light)) {
        Vec3 d = s->position - ref;
        float dist2 = length_sq(d);
        if (!(dist2 > 0)) return std::nullopt;
        LightSample ls;
        ls.p = s->position;
        ls.wi = d / std::sqrt(dist2);
        float fall = spot_falloff(*s, s->frame.to_local(-ls.wi));
        if (fall == 0) return std::nullopt;
        ls.Li = s->intensity * (fall / dist2);
        ls.pdf_sa = 1.f;
        ls.delta = true;
        return ls;
    }
    if (auto* dl = std::get_if<DirectionalLight>(&light)) {
        LightSample ls;
        ls.wi = -dl->direction;
        ls.Li = dl->irradiance;
        ls.pdf_sa = 1.f;
        ls.delta = true;
        ls.infinite = true;
        return ls;
    }
    if (auto* em = std::get_if<EnvMapLight>(&light)) {
        auto es = em->map->sample(u);
        if (!es) return std::nullopt;
        LightSample ls;
        ls.wi = es->d;
        ls.Li = es->L;
        ls.pdf_sa = es->pdf_sa;
        ls.infinite = true;
        return ls;
    }
    const auto& c = std::get<ConstantLight>(light);
    LightSample ls;
    ls.wi = square_to_uniform_sphere(u);
    ls.Li = c.radiance;
    ls.pdf_sa = environment_pdf_li_sa();
    ls.infinite = true;
    return ls;
}

Rgb environment_le(const Light& light, const Vec3& d) {
    if (auto* c = std::get_if<ConstantLight>(&light)) return c->radiance;
    if (auto* e = std::get_if<EnvMapLight>(&light)) return e->map->eval(d);
    return Rgb(0.f);
}

float environment_pdf_li_sa(const Light& light, const Vec3& d) {
    if (std::holds_alternative<ConstantLight>(light)) return environment_pdf_li_sa();
    if (auto* e = std::get_if<EnvMapLight>(&light)) return e->map->pdf_sa(d);
    return 0.f;
}

bool is_environment(const Light& light) {
    return std::holds_alternative<ConstantLight>(light) || std::holds_alternative<EnvMapLight>(light);
}

float light_pdf_li_sa(const Scene& scene, const AreaLight& light, const Vec3& ref, const SurfaceHit& hit) {
    const Shape& sh = scene.shapes()[light.shape];
    if (sh.kind == ShapeKind::Sphere) return sphere_pdf_sa(sh.sphere, ref, hit);
    Vec3 d = hit.p - ref;
    float dist2 = length_sq(d);
    if (!(dist2 > 0)) return 0.f;
    return convert_area_to_sa(sh.inv_area, dist2, absdot(hit.ng, d / std::sqrt(dist2)));
}

Rgb light_emission_towards(const Light& light, const SurfaceHit& at, const Vec3& w) {
    if (auto* a = std::get_if<AreaLight>(&light)) return area_light_le(*a, at, w) * absdot(at.ng, w);
    if (auto* p = std::get_if<PointLight>(&light)) return p->intensity;
    if (auto* s = std::get_if<SpotLight>(&light)) return s->intensity * spot_falloff(*s, s->frame.to_local(w));
    return Rgb(0.f);
}

double light_power(const Scene& scene, const Light& light) {
    if (auto* a = std::get_if<AreaLight>(&light))
        return double(average(a->radiance)) * scene.shapes()[a->shape].area * kPiD * (a->two_sided ? 2 : 1);
    if (auto* p = std::get_if<PointLight>(&light)) return 4.0 * kPiD * average(p->intensity);
    if (auto* s = std::get_if<SpotLight>(&light))
        return 2.0 * kPiD * average(s->intensity) * (1.0 - 0.5 * (std::cos(s->beam_rad) + s->cos_cutoff));
    double r = scene.bounds().empty() ? 1.0 : std::max(1e-6f, scene.bounds().radius());
    if (auto* d = std::get_if<DirectionalLight>(&light)) return kPiD * r * r * average(d->irradiance);
    if (auto* e = std::get_if<EnvMapLight>(&light)) return kPiD * r * r * e->map->integral();
    const auto& c = std::get<ConstantLight>(light);
    return 4.0 * kPiD * kPiD * r * r * average(c.radiance);
}

bool light_is_delta(const Light& light) {
    return std::holds_alternative<PointLight>(light) || std::holds_alternative<SpotLight>(light) ||
           std::holds_alternative<DirectionalLight>(light);
}

}  // namespace omega
