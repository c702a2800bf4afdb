// find_parallelogram, and the area sampling of light shapes that uses it (shape_area_sample.h):
// which meshes are taken for a parallelogram, that every sampled point lies in the triangle it
// names, and a chi-square test of light subpath origins against the uniform area density, in
// the rectangle's own coordinates (through the inverse of its placement, not the sampler's edges).
#include <gtest/gtest.h>

#include <algorithm>

#include "chi2.h"
#include "light/light_emission.h"
#include "render_harness.h"
#include "sampling/rng.h"
#include "scene/parallelogram.h"
#include "scene/scene.h"
#include "scene/shape_area_sample.h"

namespace omega {
namespace {

// A rotated, sheared, scaled and moved placement: its image of the square is no rectangle.
Mat4 sheared() {
    Mat4 shear;
    shear(0, 1) = 0.6;  // x += 0.6 y
    return Mat4::translate({0.3, -0.2, 2.0}) * Mat4::rotate({1, 0.3, 0.2}, 160) * shear * Mat4::scale({1.5, 0.7, 1});
}

TriangleMesh placed(TriangleMesh m, const Mat4& to_world) {
    for (Vec3& p : m.positions) p = Vec3(to_world.point(Vec3d(p)));
    return m;
}

Vec3d corner(const TriangleMesh& m, uint32_t t, int k) { return Vec3d(m.positions[m.indices[3 * t + uint32_t(k)]]); }

double triangle_area(const TriangleMesh& m, uint32_t t) {
    return 0.5 * length(cross(corner(m, t, 1) - corner(m, t, 0), corner(m, t, 2) - corner(m, t, 0)));
}

// The smallest barycentric coordinate of p (in the triangle's plane) in triangle t: >= 0 inside.
double min_barycentric(const TriangleMesh& m, uint32_t t, const Vec3& p) {
    const Vec3d a = corner(m, t, 0), b = corner(m, t, 1), c = corner(m, t, 2), q(p);
    const Vec3d n = cross(b - a, c - a);
    const double nn = dot(n, n);
    const double l0 = dot(cross(c - b, q - b), n) / nn, l1 = dot(cross(a - c, q - c), n) / nn;
    return std::min({l0, l1, 1.0 - l0 - l1});
}

// How much rounding by `err` (per axis) may move a barycentric coordinate of triangle t: by
// |err| over the triangle's smallest altitude.
double barycentric_slack(const TriangleMesh& m, uint32_t t, const Vec3& err) {
    const Vec3d a = corner(m, t, 0), b = corner(m, t, 1), c = corner(m, t, 2);
    const double longest = std::max({length(b - a), length(c - b), length(a - c)});
    return length(Vec3d(err)) / (2.0 * triangle_area(m, t) / longest);
}

double distance_to_plane(const TriangleMesh& m, uint32_t t, const Vec3& p) {
    const Vec3d a = corner(m, t, 0), n = normalize(cross(corner(m, t, 1) - a, corner(m, t, 2) - a));
    return std::abs(dot(Vec3d(p) - a, n));
}

TriangleMesh reversed_winding(TriangleMesh m) {
    for (size_t t = 0; t < m.triangle_count(); ++t) std::swap(m.indices[3 * t + 1], m.indices[3 * t + 2]);
    return m;
}

TEST(Parallelogram, FoundForARectangleUnderAnyAffinePlacement) {
    for (const TriangleMesh& m : {make_rectangle(), placed(make_rectangle(), sheared()),
                                  reversed_winding(placed(make_rectangle(), sheared()))}) {
        auto q = find_parallelogram(m);
        ASSERT_TRUE(q);
        EXPECT_NE(q->tri_a, q->tri_b);
        // Its four corners are the mesh's four vertices.
        for (const Vec3& c : {q->o, q->o + q->e1, q->o + q->e2, q->o + q->e1 + q->e2}) {
            double nearest = 1e30;
            for (const Vec3& p : m.positions) nearest = std::min(nearest, length(Vec3d(c) - Vec3d(p)));
            EXPECT_LT(nearest, 1e-5);
        }
        const double area = length(cross(Vec3d(q->e1), Vec3d(q->e2)));
        EXPECT_NEAR(area, triangle_area(m, 0) + triangle_area(m, 1), 1e-6 * area);
    }
}

TEST(Parallelogram, NotFoundForOtherMeshes) {
    TriangleMesh kite = make_rectangle();
    kite.positions[2] = {1.5f, 1.2f, 0};  // the far corner moved in the plane
    TriangleMesh folded = make_rectangle();
    folded.positions[3].z = 0.3f;  // out of the plane
    TriangleMesh apart = make_rectangle();
    apart.positions.push_back({3, 3, 0});
    apart.indices = {0, 1, 2, 0, 3, 4};  // share only a vertex
    TriangleMesh inconsistent = make_rectangle();
    std::swap(inconsistent.indices[4], inconsistent.indices[5]);  // the second triangle faces away
    TriangleMesh one = make_rectangle();
    one.indices.resize(3);
    TriangleMesh flat = make_rectangle();
    flat.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {1, 0, 0}};  // no area
    for (const TriangleMesh& m : {kite, folded, apart, inconsistent, one, flat, make_cube(), make_disk()})
        EXPECT_FALSE(find_parallelogram(m));
}

// Each point lies inside the triangle it names (the light sample's normal and, for light
// subpaths, the primitive whose self-hits are filtered come from it), on the mesh within its
// error bound, and (a, b) = u puts every point of the square somewhere on the light.
TEST(Parallelogram, SampledPointsLieInTheTriangleTheyName) {
    for (const TriangleMesh& m : {placed(make_rectangle(), sheared()), reversed_winding(placed(make_rectangle(), sheared())),
                                  placed(make_rectangle(), Mat4::translate({1e4, -3e4, 2e4}) * Mat4::scale({2, 3, 1}))}) {
        auto q = find_parallelogram(m);
        ASSERT_TRUE(q);
        Rng rng = Rng::for_sample(5, 0, 0);
        int in_a = 0;
        for (int i = 0; i < 100'000; ++i) {
            Vec2 u{rng.next_1d(), rng.next_1d()};
            if (i == 0) u = {0, 0};
            if (i == 1) u = {0x1.fffffep-1f, 0x1.fffffep-1f};
            const AreaPoint s = sample_parallelogram(*q, u);
            ASSERT_GE(min_barycentric(m, s.tri, s.p), -barycentric_slack(m, s.tri, s.p_error)) << "u " << u.x << " " << u.y;
            ASSERT_LE(distance_to_plane(m, s.tri, s.p), double(length(s.p_error)) + 1e-30);
            in_a += s.tri == q->tri_a;
        }
        // The two halves have equal area.
        EXPECT_NEAR(in_a / 100'000.0, 0.5, 0.01);
    }
}

SceneDesc light_scene(const Mat4& to_world, bool flip) {
    SceneDesc d = test::empty_scene(4, 4);
    d.materials["black"] = MaterialDesc{"black", BlackBsdf{}, {}};
    ShapeDesc s;
    s.type = ShapeType::Rectangle;
    s.to_world = to_world;
    s.material = "black";
    s.flip_normals = flip;
    s.emitter = EmitterDesc{Rgb(1.f), false};
    d.shapes.push_back(s);
    return d;
}

// Light subpath origins on a sheared rectangle, mapped back to its square [-1, 1]^2 by the
// inverse of its placement: uniform by area there means density 1/4 (the map is affine). Also
// pdf_pos is 1 / area, the normal is the named triangle's, and the light is taken for a
// parallelogram (or this would test the triangle path).
TEST(ShapeAreaSample, LightOriginsAreUniformOnAShearedRectangle) {
    for (bool flip : {false, true}) {
        auto scene = Scene::build(light_scene(sheared(), flip));
        const Shape& sh = scene->shapes()[0];
        ASSERT_TRUE(sh.parallelogram);
        const Mat4 inv = *sheared().inverse();
        const Light& light = scene->lights()[0];
        size_t bad = 0;
        test::Chi2Options opt;
        opt.sample_count = 400'000;
        opt.test_count = 2;
        opt.seed = flip ? 8 : 7;
        auto sampler = [&](Rng& rng) -> std::optional<test::PointSample> {
            auto e = light_sample_le(*scene, light, {rng.next_1d(), rng.next_1d()}, {rng.next_1d(), rng.next_1d()});
            if (!e) return std::nullopt;
            if (std::abs(e->pdf_pos * sh.area - 1.0) > 1e-9) ++bad;
            if (e->origin.ng != sh.face_normals[e->origin.prim]) ++bad;
            if (min_barycentric(sh.mesh, e->origin.prim, e->origin.p) < -barycentric_slack(sh.mesh, e->origin.prim, e->origin.p_error))
                ++bad;
            const Vec3d l = inv.point(Vec3d(e->origin.p));
            return test::PointSample{Vec2{float(l.x), float(l.y)}, 0.25};
        };
        auto r = test::chi2_plane(sampler, [](Vec2) { return 0.25; }, {-1, -1, 1, 1}, opt, 32, 32);
        test::print_result(flip ? "sheared rectangle origins, flipped" : "sheared rectangle origins", r);
        EXPECT_TRUE(r.passed) << r.message;
        EXPECT_EQ(bad, 0u);
    }
}

// The same check can fail: the triangle pick's density, had it given one half 55% of the
// points, is rejected.
TEST(ShapeAreaSample, TheOriginCheckRejectsAnUnevenSplit) {
    auto scene = Scene::build(light_scene(sheared(), false));
    const Mat4 inv = *sheared().inverse();
    test::Chi2Options opt;
    opt.sample_count = 400'000;
    opt.seed = 9;
    auto sampler = [&](Rng& rng) -> std::optional<test::PointSample> {
        Vec2 u{rng.next_1d(), rng.next_1d()};
        // Move 10% of one half's points to the other.
        if (u.x < u.y && rng.next_1d() < 0.1f) std::swap(u.x, u.y);
        const AreaPoint s = sample_shape_area(scene->shapes()[0], u);
        const Vec3d l = inv.point(Vec3d(s.p));
        return test::PointSample{Vec2{float(l.x), float(l.y)}, 0.25};
    };
    auto r = test::chi2_plane(sampler, [](Vec2) { return 0.25; }, {-1, -1, 1, 1}, opt, 32, 32);
    EXPECT_FALSE(r.passed);
}

}  // namespace
}  // namespace omega
