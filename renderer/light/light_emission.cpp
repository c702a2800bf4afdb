#include "light/light_emission.h"

#include <cmath>

#include "math/float_bits.h"
#include "sampling/warp.h"
#include "scene/scene.h"
#include "scene/shape_area_sample.h"
#include "scene/spawn.h"

namespace omega {

namespace {

// Direction sampled cosine-weighted about n; two-sided emitters pick a side with probability 1/2.
Vec3 sample_cosine_about(const Vec3& n, Vec2 u, bool two_sided, double& pdf_dir) {
    bool flip = false;
    if (two_sided) {
        flip = u.x < 0.5f;
        u.x = flip ? u.x * 2.f : (u.x - 0.5f) * 2.f;
        u.x = std::min(u.x, 0x1.fffffep-1f);
    }
    Vec3 local = square_to_cosine_hemisphere(u);
    pdf_dir = double(local.z) * kInvPi * (two_sided ? 0.5 : 1.0);
    Frame f = Frame::from_normal(flip ? -n : n);
    return f.to_world(local);
}

}  // namespace

std::optional<LightEmission> light_sample_le(const Scene& scene, const Light& light, Vec2 u_pos, Vec2 u_dir) {
    LightEmission e;
    if (auto* a = std::get_if<AreaLight>(&light)) {
        const Shape& sh = scene.shapes()[a->shape];
        SurfaceHit& o = e.origin;
        o.shape = a->shape;
        o.planar = true;
        if (sh.kind == ShapeKind::Sphere) {
            Vec3 n = square_to_uniform_sphere(u_pos);
            Vec3d pd = sh.sphere.center + Vec3d(n) * sh.sphere.radius;
            o.p = Vec3(pd);
            o.p_error = abs(o.p) * gamma_bound(5);
            o.ng = o.ns = sh.flip_normals ? -n : n;
            o.planar = false;
        } else {
            const AreaPoint q = sample_shape_area(sh, u_pos);
            o.p = q.p;
            o.p_error = q.p_error;
            o.ng = o.ns = sh.face_normals[q.tri];
            o.prim = q.tri;
            o.planar = true;
        }
        e.pdf_pos = 1.0 / sh.area;
        Vec3 w = sample_cosine_about(o.ng, u_dir, a->two_sided, e.pdf_dir);
        if (!(e.pdf_dir > 0)) return std::nullopt;
        e.ray = spawn_ray(o, w);
        e.Le = a->radiance;
        return e;
    }
    e.origin.planar = false;  // non-area lights: no surface to offset from, no self-hit to filter
    if (auto* p = std::get_if<PointLight>(&light)) {
        e.ray.o = p->position;
        e.ray.d = square_to_uniform_sphere(u_dir);
        e.origin.p = p->position;
        e.pdf_dir = uniform_sphere_pdf_sa();
        e.delta_pos = true;
        e.Le = p->intensity;
        return e;
    }
    if (auto* s = std::get_if<SpotLight>(&light)) {
        Vec3 local = square_to_uniform_cone(u_dir, s->cos_cutoff);
        float cos_t = local.z;
        float fall;
        if (cos_t <= s->cos_cutoff) return std::nullopt;
        float angle = std::acos(std::min(cos_t, 1.f));
        fall = angle <= s->beam_rad || s->cutoff_rad <= s->beam_rad
                   ? 1.f
                   : std::clamp((s->cutoff_rad - angle) / (s->cutoff_rad - s->beam_rad), 0.f, 1.f);
        e.ray.o = s->position;
        e.ray.d = s->frame.to_world(local);
        e.origin.p = s->position;
        e.pdf_dir = uniform_cone_pdf_sa(local, s->cos_cutoff);
        e.delta_pos = true;
        e.Le = s->intensity * fall;
        return e;
    }
    // Lights at infinity: a disk of the scene's bounding radius, perpendicular to the direction.
    const SceneBounds& b = scene.bounds();
    Vec3 c = b.empty() ? Vec3(0.f) : b.center();
    float r = b.empty() ? 1.f : std::max(b.radius(), 1e-6f);
    Vec3 dir;
    if (auto* d = std::get_if<DirectionalLight>(&light)) {
        dir = d->direction;
        e.delta_dir = true;
        e.Le = d->irradiance;
        e.pdf_dir = 1;
    } else if (auto* em = std::get_if<EnvMapLight>(&light)) {
        auto es = em->map->sample(u_dir);
        if (!es) return std::nullopt;
        dir = -es->d;  // arriving from the sampled direction
        e.Le = es->L;
        e.pdf_dir = es->pdf_sa;
    } else {
        const auto& cl = std::get<ConstantLight>(light);
        dir = -square_to_uniform_sphere(u_dir);  // arriving from the sampled direction
        e.Le = cl.radiance;
        e.pdf_dir = uniform_sphere_pdf_sa();
    }
    Frame f = Frame::from_normal(dir);
    Vec2 disk = square_to_uniform_disk_concentric(u_pos);
    e.ray.o = c - dir * r + (f.s * disk.x + f.t * disk.y) * r;
    e.ray.d = dir;
    e.origin.p = e.ray.o;
    e.pdf_pos = 1.0 / (kPiD * double(r) * r);
    e.infinite = true;
    return e;
}

void light_pdf_le(const Scene& scene, const Light& light, const Vec3& n, const Vec3& w, double& pdf_pos,
                  double& pdf_dir) {
    if (auto* a = std::get_if<AreaLight>(&light)) {
        pdf_pos = 1.0 / scene.shapes()[a->shape].area;
        double c = dot(n, w);
        if (a->two_sided) pdf_dir = std::abs(c) * kInvPi * 0.5;
        else pdf_dir = c > 0 ? c * kInvPi : 0.0;
        return;
    }
    if (std::holds_alternative<PointLight>(light)) {
        pdf_pos = 1;
        pdf_dir = uniform_sphere_pdf_sa();
        return;
    }
    if (auto* s = std::get_if<SpotLight>(&light)) {
        pdf_pos = 1;
        pdf_dir = uniform_cone_pdf_sa(s->frame.to_local(w), s->cos_cutoff);
        return;
    }
    const SceneBounds& b = scene.bounds();
    float r = b.empty() ? 1.f : std::max(b.radius(), 1e-6f);
    pdf_pos = 1.0 / (kPiD * double(r) * r);
    pdf_dir = std::holds_alternative<DirectionalLight>(light) ? 1.0 : infinite_light_pdf_dir(light, w);
}

double infinite_light_pdf_dir(const Light& light, const Vec3& w) {
    if (std::holds_alternative<ConstantLight>(light)) return uniform_sphere_pdf_sa();
    // w is the direction of travel: the light arrives from -w, which NEE samples with this density.
    if (auto* e = std::get_if<EnvMapLight>(&light)) return e->map->pdf_sa(-w);
    return 0;  // a delta direction is never hit by chance
}

}  // namespace omega
