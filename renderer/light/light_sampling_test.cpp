// Chi-square tests of next-event light sampling: the directions light_sample_li produces from a
// reference point must follow the solid-angle density the path tracer uses for MIS
// (selection pmf x light_pdf_li_sa), found independently by tracing the direction.
#include <gtest/gtest.h>

#include "chi2.h"
#include "render_harness.h"

namespace omega {
namespace {

constexpr int kTests = 8;

// Density of direction w from ref under "pick a light by power, then sample it".
double traced_pdf_sa(const Scene& scene, const Vec3& ref, const Vec3& w) {
    Ray ray;
    ray.o = ref;
    ray.d = w;
    SurfaceHit hit;
    double pdf = 0;
    int env = scene.environment_light();
    if (env >= 0) pdf += scene.light_selection().pmf(size_t(env)) * environment_pdf_li_sa();
    if (!scene.intersect(ray, hit)) return pdf;
    const Shape& sh = scene.shapes()[hit.shape];
    if (sh.light < 0) return pdf;
    const auto& al = std::get<AreaLight>(scene.lights()[size_t(sh.light)]);
    if (is_black(area_light_le(al, hit, -w))) return pdf;
    return pdf + scene.light_selection().pmf(size_t(sh.light)) * light_pdf_li_sa(scene, al, ref, hit);
}

test::Chi2Result run(const Scene& scene, const Vec3& ref, uint64_t seed) {
    test::Chi2Options opt;
    opt.sample_count = 400'000;
    opt.test_count = kTests;
    opt.seed = seed;
    auto sampler = [&](Rng& rng) -> std::optional<test::DirSample> {
        const auto& sel = scene.light_selection();
        size_t i = sel.sample(rng.next_1d());
        Vec2 u{rng.next_1d(), rng.next_1d()};
        auto ls = light_sample_li(scene, scene.lights()[i], ref, u);
        if (!ls) return std::nullopt;
        // The tracer's view of the same direction: a different light may be in front.
        return test::DirSample{ls->wi, traced_pdf_sa(scene, ref, ls->wi)};
    };
    auto pdf = [&](const Vec3& w) { return traced_pdf_sa(scene, ref, w); };
    return test::chi2_sphere(sampler, pdf, opt);
}

// A sphere seen from outside covers a cone that may be tiny: test in the cone's own coordinates,
// u = (1 - cos theta) / (1 - cos theta_max), v = phi / 2pi, where the density is uniform if the
// sampler is right and the silhouette falls exactly on a cell edge.
test::Chi2Result run_cone(const Scene& scene, const Vec3& ref, const Vec3d& center, double radius, uint64_t seed) {
    Vec3d axis = normalize(center - Vec3d(ref));
    Frame f = Frame::from_normal(Vec3(axis));
    double sin2_max = radius * radius / length_sq(center - Vec3d(ref));
    double one_minus_cos_max = sin2_max / (1.0 + std::sqrt(1.0 - sin2_max));
    auto to_plane = [&](const Vec3& w) {
        Vec3 l = f.to_local(w);
        double omc = (double(l.x) * l.x + double(l.y) * l.y) / (1.0 + l.z);  // 1 - cos, without cancellation
        double phi = std::atan2(double(l.y), double(l.x));
        if (phi < 0) phi += 2 * kPiD;
        return Vec2{float(omc / one_minus_cos_max), float(phi / (2 * kPiD))};
    };
    auto from_plane = [&](Vec2 p) {
        double omc = double(p.x) * one_minus_cos_max;
        double cos_t = 1.0 - omc, sin_t = std::sqrt(std::max(0.0, omc * (2.0 - omc)));
        double phi = 2 * kPiD * p.y;
        return f.to_world(Vec3(Vec3d{sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t}));
    };
    const double jacobian = 2 * kPiD * one_minus_cos_max;  // d(omega) = jacobian du dv
    test::Chi2Options opt;
    opt.sample_count = 400'000;
    opt.test_count = kTests;
    opt.seed = seed;
    auto sampler = [&](Rng& rng) -> std::optional<test::PointSample> {
        size_t i = scene.light_selection().sample(rng.next_1d());
        auto ls = light_sample_li(scene, scene.lights()[i], ref, {rng.next_1d(), rng.next_1d()});
        if (!ls) return std::nullopt;
        return test::PointSample{to_plane(ls->wi), traced_pdf_sa(scene, ref, ls->wi) * jacobian};
    };
    auto pdf = [&](Vec2 p) { return traced_pdf_sa(scene, ref, from_plane(p)) * jacobian; };
    return test::chi2_plane(sampler, pdf, {0, 0, 1, 1}, opt, 32, 32);
}

SceneDesc base() {
    SceneDesc d = test::empty_scene(4, 4);
    d.materials["black"] = MaterialDesc{"black", BlackBsdf{}, {}};
    return d;
}

ShapeDesc sphere_light(Vec3d c, double r) {
    ShapeDesc s;
    s.type = ShapeType::Sphere;
    s.center = c;
    s.radius = r;
    s.material = "black";
    s.emitter = EmitterDesc{Rgb(1.f), false};
    return s;
}

ShapeDesc rect_light(const Mat4& m, bool two_sided) {
    ShapeDesc s;
    s.type = ShapeType::Rectangle;
    s.to_world = m;
    s.material = "black";
    s.emitter = EmitterDesc{Rgb(2.f), two_sided};
    return s;
}

TEST(LightSamplingChi2, SphereFromOutside) {
    SceneDesc d = base();
    d.shapes.push_back(sphere_light({0, 0, 3}, 1.0));
    auto scene = Scene::build(d);
    auto r = run_cone(*scene, {0.2f, -0.1f, 0}, {0, 0, 3}, 1.0, 1);
    test::print_result("sphere outside", r);
    EXPECT_TRUE(r.passed) << r.message;
}

TEST(LightSamplingChi2, SmallDistantSphere) {
    // Subtends under 1.5 degrees: the Taylor branch of cone sampling.
    SceneDesc d = base();
    d.shapes.push_back(sphere_light({0, 0, 40}, 0.8));
    auto scene = Scene::build(d);
    auto r = run_cone(*scene, {0, 0, 0}, {0, 0, 40}, 0.8, 2);
    test::print_result("small sphere", r);
    EXPECT_TRUE(r.passed) << r.message;
}

TEST(LightSamplingChi2, SphereFromInside) {
    SceneDesc d = base();
    d.shapes.push_back(sphere_light({0, 0, 0}, 2.0));
    d.shapes.back().emitter->two_sided = true;
    auto scene = Scene::build(d);
    auto r = run(*scene, {0.5f, 0.3f, -0.7f}, 3);
    test::print_result("sphere inside", r);
    EXPECT_TRUE(r.passed) << r.message;
}

TEST(LightSamplingChi2, TiltedOneSidedRectangle) {
    SceneDesc d = base();
    // Faces roughly towards -z (towards the reference point), tilted so cosines vary.
    d.shapes.push_back(rect_light(Mat4::translate({0.3, 0, 1.5}) * Mat4::rotate({1, 0.2, 0}, 150) *
                                      Mat4::scale({1.5, 0.7, 1}),
                                  false));
    auto scene = Scene::build(d);
    ASSERT_TRUE(scene->shapes()[0].parallelogram);
    auto r = run(*scene, {0, 0, 0}, 4);
    test::print_result("tilted rectangle", r);
    EXPECT_TRUE(r.passed) << r.message;
}

TEST(LightSamplingChi2, ShearedRectangleWithFlippedNormals) {
    // A parallelogram that is no rectangle, sampled as one (scene/parallelogram.h), with the
    // winding reversed by flip_normals.
    SceneDesc d = base();
    Mat4 shear;
    shear(0, 1) = 0.7;
    d.shapes.push_back(rect_light(Mat4::translate({-0.2, 0.1, 1.2}) * Mat4::rotate({0.3, 1, 0}, 20) * shear *
                                      Mat4::scale({1.2, 0.5, 1}),
                                  true));
    d.shapes.back().flip_normals = true;
    auto scene = Scene::build(d);
    ASSERT_TRUE(scene->shapes()[0].parallelogram);
    auto r = run(*scene, {0, 0, 0}, 8);
    test::print_result("sheared rectangle", r);
    EXPECT_TRUE(r.passed) << r.message;
}

TEST(LightSamplingChi2, DiskMeshByArea) {
    // 64 triangles: picks a triangle by area, then a point uniformly in it.
    SceneDesc d = base();
    ShapeDesc disk = rect_light(Mat4::translate({0, 0, 1}) * Mat4::rotate({1, 0, 0}, 180) * Mat4::scale({2, 1, 1}), false);
    disk.type = ShapeType::Disk;
    d.shapes.push_back(disk);
    auto scene = Scene::build(d);
    ASSERT_FALSE(scene->shapes()[0].parallelogram);
    auto r = run(*scene, {0.4f, 0, 0}, 5);
    test::print_result("disk mesh", r);
    EXPECT_TRUE(r.passed) << r.message;
}

TEST(LightSamplingChi2, SeveralLightsByPowerWithEnvironment) {
    SceneDesc d = base();
    d.shapes.push_back(sphere_light({0, 0, 3}, 0.7));
    d.shapes.push_back(rect_light(Mat4::translate({0, 0, -2}), true));
    LightDesc env;
    env.type = LightType::Constant;
    env.radiance = Rgb(0.05f);
    d.lights.push_back(env);
    auto scene = Scene::build(d);
    ASSERT_EQ(scene->lights().size(), 3u);
    auto r = run(*scene, {0.1f, 0.2f, 0.3f}, 6);
    test::print_result("lights by power", r);
    EXPECT_TRUE(r.passed) << r.message;
}

// The harness is able to fail: claiming the sphere is twice as bright in the pdf used for the
// check (a wrong selection pmf) is rejected.
TEST(LightSamplingChi2, RejectsAWrongSelectionPmf) {
    SceneDesc d = base();
    d.shapes.push_back(sphere_light({0, 0, 3}, 0.7));
    d.shapes.push_back(rect_light(Mat4::translate({0, 0, -2}), true));
    auto scene = Scene::build(d);
    test::Chi2Options opt;
    opt.sample_count = 400'000;
    opt.test_count = kTests;
    Vec3 ref{0, 0, 0};
    auto pdf = [&](const Vec3& w) {
        double p = traced_pdf_sa(*scene, ref, w);
        return w.z > 0 ? p * 1.2 : p * 0.8;
    };
    auto sampler = [&](Rng& rng) -> std::optional<test::DirSample> {
        size_t i = scene->light_selection().sample(rng.next_1d());
        auto ls = light_sample_li(*scene, scene->lights()[i], ref, {rng.next_1d(), rng.next_1d()});
        if (!ls) return std::nullopt;
        return test::DirSample{ls->wi, pdf(ls->wi)};
    };
    auto r = test::chi2_sphere(sampler, pdf, opt);
    EXPECT_FALSE(r.passed);
}

}  // namespace
}  // namespace omega
