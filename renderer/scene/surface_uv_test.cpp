// SurfaceHit::uv on every shape at known points, in Mitsuba 3's conventions (rectangle, cube
// faces, sphere, disk, meshes with and without uvs).
#include <gtest/gtest.h>

#include <cmath>

#include "scene/scene.h"
#include "scene/test_helpers.h"
#include "test_images.h"

using namespace omega;
using omega::test::TempDir;

namespace {

struct UvScene {
    TempDir dir;
    SceneDesc d;
    UvScene() {
        auto png = (dir.path / "t.png").string();
        test::write_image_u8(png, 1, 1, 3, {128, 128, 128});
        d.path = (dir.path / "s.yaml").string();
        MaterialDesc m;
        m.name = "tex";
        m.bsdf = DiffuseBsdf{};
        m.reflectance_texture = BitmapDesc{png};
        d.materials["tex"] = m;
        d.materials["plain"] = MaterialDesc{"plain", DiffuseBsdf{}, {}};
    }
    void add(ShapeType t, const Mat4& to_world = {}, const std::string& material = "tex") {
        ShapeDesc s;
        s.type = t;
        s.to_world = to_world;
        s.material = material;
        d.shapes.push_back(s);
    }
};

// The uv where a ray from `from` towards `to` hits the scene.
Vec2 uv_at(const Scene& scene, Vec3 from, Vec3 to) {
    Ray r{from, normalize(to - from)};
    SurfaceHit h;
    EXPECT_TRUE(scene.intersect(r, h)) << to.x << " " << to.y << " " << to.z;
    return h.uv;
}

void expect_uv(Vec2 got, float u, float v, float eps = 2e-6f) {
    EXPECT_NEAR(got.x, u, eps);
    EXPECT_NEAR(got.y, v, eps);
}

TEST(SurfaceUv, RectangleMapsMinusOneOneSquareToUnitSquare) {
    UvScene s;
    s.add(ShapeType::Rectangle, Mat4::translate({0, 0, -1}) * Mat4::rotate({0, 0, 1}, 90) * Mat4::scale({2, 3, 1}));
    auto scene = Scene::build(s.d);
    // Local (x, y) = (0.5, -0.5) -> uv (0.75, 0.25); world: scale (1, -1.5), rotate 90 -> (1.5, 1).
    expect_uv(uv_at(*scene, {1.5f, 1.f, 5.f}, {1.5f, 1.f, -1.f}), 0.75f, 0.25f);
    expect_uv(uv_at(*scene, {0, 0, 5.f}, {0, 0, -1.f}), 0.5f, 0.5f);
    // Local (-0.9, 0.8) -> (0.05, 0.9); world (-1.8, 2.4) rotated -> (-2.4, -1.8).
    expect_uv(uv_at(*scene, {-2.4f, -1.8f, 5.f}, {-2.4f, -1.8f, -1.f}), 0.05f, 0.9f);
}

TEST(SurfaceUv, CubeFacesFollowMitsubasVertexTable) {
    // Mitsuba 3's cube mesh (src/shapes/cube.cpp): each face's four corners and their uvs.
    struct Corner { Vec3 p; Vec2 uv; };
    const Corner table[6][4] = {
        {{{1, -1, -1}, {0, 1}}, {{1, -1, 1}, {1, 1}}, {{-1, -1, 1}, {1, 0}}, {{-1, -1, -1}, {0, 0}}},   // -y
        {{{1, 1, -1}, {0, 1}}, {{-1, 1, -1}, {1, 1}}, {{-1, 1, 1}, {1, 0}}, {{1, 1, 1}, {0, 0}}},       // +y
        {{{1, -1, -1}, {0, 1}}, {{1, 1, -1}, {1, 1}}, {{1, 1, 1}, {1, 0}}, {{1, -1, 1}, {0, 0}}},       // +x
        {{{1, -1, 1}, {0, 1}}, {{1, 1, 1}, {1, 1}}, {{-1, 1, 1}, {1, 0}}, {{-1, -1, 1}, {0, 0}}},       // +z
        {{{-1, -1, 1}, {0, 1}}, {{-1, 1, 1}, {1, 1}}, {{-1, 1, -1}, {1, 0}}, {{-1, -1, -1}, {0, 0}}},   // -x
        {{{1, 1, -1}, {0, 1}}, {{1, -1, -1}, {1, 1}}, {{-1, -1, -1}, {1, 0}}, {{-1, 1, -1}, {0, 0}}},   // -z
    };
    UvScene s;
    s.add(ShapeType::Cube);
    auto scene = Scene::build(s.d);
    for (const auto& face : table) {
        Vec3 c = (face[0].p + face[2].p) * 0.5f;  // the face centre is its outward normal
        for (const Corner& k : face) {
            // A point 80% of the way from the centre to the corner, seen from outside along -n.
            Vec3 p = c + (k.p - c) * 0.8f;
            Vec2 uv = uv_at(*scene, p + c * 3.f, p);
            expect_uv(uv, 0.5f + 0.8f * (k.uv.x - 0.5f), 0.5f + 0.8f * (k.uv.y - 0.5f), 1e-5f);
        }
    }
}

TEST(SurfaceUv, SphereIsMitsubasSphericalMap) {
    UvScene s;
    ShapeDesc sp;
    sp.type = ShapeType::Sphere;
    sp.center = {1, 2, 3};
    sp.radius = 2;
    sp.material = "tex";
    s.d.shapes.push_back(sp);
    auto scene = Scene::build(s.d);
    const Vec3 c{1, 2, 3};
    auto on = [&](double theta, double phi) {  // local direction, z up
        return Vec3(Vec3d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)));
    };
    // u = phi / 2 pi, v = theta / pi (theta from +z).
    for (auto [theta, phi] : {std::pair{kPiD / 2, kPiD / 2}, {kPiD / 3, 1.25 * kPiD}, {0.9 * kPiD, 0.1}, {0.2, 1.9 * kPiD}}) {
        Vec3 n = on(theta, phi);
        expect_uv(uv_at(*scene, c + n * 5.f, c), float(phi / (2 * kPiD)), float(theta / kPiD), 1e-5f);
    }
    // The sphere's own frame turns with its to_world: rotated 90 degrees about z, local +x is world +y.
    UvScene r;
    sp.center = {0, 0, 0};
    sp.radius = 1;
    sp.to_world = Mat4::rotate({0, 0, 1}, 90);
    r.d.shapes.push_back(sp);
    auto rs = Scene::build(r.d);
    const float h = 5.f * std::sqrt(0.5f);
    expect_uv(uv_at(*rs, {-h, h, 0}, {0, 0, 0}), 0.125f, 0.5f, 1e-5f);  // local (1, 1, 0) / sqrt 2
    expect_uv(uv_at(*rs, {-5, 0, 0}, {0, 0, 0}), 0.25f, 0.5f, 1e-5f);
}

TEST(SurfaceUv, DiskIsRadiusAndAngle) {
    UvScene s;
    s.add(ShapeType::Disk, Mat4::scale({3, 3, 1}));
    auto scene = Scene::build(s.d);
    expect_uv(uv_at(*scene, {1.5f, 0.01f, 2}, {1.5f, 0.01f, 0}), float(std::hypot(0.5, 0.01 / 3)),
              float(std::atan2(0.01, 1.5) / (2 * kPiD)), 1e-5f);
    expect_uv(uv_at(*scene, {0, -1.5f, 2}, {0, -1.5f, 0}), 0.5f, 0.75f, 1e-5f);
    expect_uv(uv_at(*scene, {-0.9f, 0.9f * std::sqrt(3.f), 2}, {-0.9f, 0.9f * std::sqrt(3.f), 0}), 0.6f, 1.f / 3.f, 1e-5f);
}

TEST(SurfaceUv, MeshUvsAreInterpolatedAndFlippedLikeMitsuba) {
    UvScene s;
    auto obj = s.dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.2 0.1\nvt 0.8 0.1\nvt 0.2 0.9\nf 1/1 2/2 3/3\n");
    ShapeDesc m;
    m.type = ShapeType::Mesh;
    m.file = obj.string();
    m.material = "tex";
    s.d.shapes.push_back(m);
    m.to_world = Mat4::translate({5, 0, 0});
    m.flip_tex_coords = false;
    s.d.shapes.push_back(m);
    auto noval = s.dir.write("plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    m.file = noval.string();
    m.to_world = Mat4::translate({10, 0, 0});
    s.d.shapes.push_back(m);
    auto scene = Scene::build(s.d);
    // At (0.25, 0.5): barycentrics b1 = 0.25, b2 = 0.5 -> file uv (0.35, 0.5).
    expect_uv(uv_at(*scene, {0.25f, 0.5f, 1}, {0.25f, 0.5f, 0}), 0.35f, 1.f - 0.5f, 1e-5f);      // v' = 1 - v
    expect_uv(uv_at(*scene, {0.25f, 0.1f, 1}, {0.25f, 0.1f, 0}), 0.35f, 1.f - 0.18f, 1e-5f);
    expect_uv(uv_at(*scene, {5.25f, 0.1f, 1}, {5.25f, 0.1f, 0}), 0.35f, 0.18f, 1e-5f);           // as stored
    expect_uv(uv_at(*scene, {10.25f, 0.1f, 1}, {10.25f, 0.1f, 0}), 0.25f, 0.1f, 1e-5f);          // no uvs: (b1, b2)
}

TEST(SurfaceUv, UntexturedShapesLeaveUvAtZero) {
    UvScene s;
    s.add(ShapeType::Rectangle, {}, "plain");
    auto scene = Scene::build(s.d);
    expect_uv(uv_at(*scene, {0.5f, 0.5f, 1}, {0.5f, 0.5f, 0}), 0, 0);
    EXPECT_EQ(scene->shapes()[0].uv_map, UvMap::None);
}

}  // namespace
