// The generated primitives (rectangle, cube, disk) are flat per triangle, so Scene::intersect
// gives them their face normal as the shading normal, bit for bit: interpolating their vertex
// normals would only round, and a shading normal off the geometric one by an ulp costs every
// hit the interpolation and makes Veach's shading correction a product of near-ones.
#include <gtest/gtest.h>

#include "render_harness.h"
#include "sampling/rng.h"
#include "sampling/warp.h"
#include "scene/scene.h"
#include "scene/scene_parser.h"
#include "scene/test_helpers.h"

namespace omega {
namespace {

TEST(FlatPrimitives, ShadingNormalIsTheFaceNormal) {
    for (ShapeType type : {ShapeType::Rectangle, ShapeType::Cube, ShapeType::Disk}) {
        SceneDesc d = test::empty_scene(4, 4);
        d.materials["white"] = test::diffuse("white", Rgb(0.5f));
        ShapeDesc s;
        s.type = type;
        s.material = "white";
        s.to_world = Mat4::rotate({0.3, 1, 0.2}, 37) * Mat4::scale({1.5, 0.8, 1.2});
        d.shapes.push_back(s);
        auto scene = Scene::build(d);
        Rng rng = Rng::for_sample(3, 0, 0);
        int hits = 0;
        for (int i = 0; i < 2000; ++i) {
            Ray ray;
            ray.o = square_to_uniform_sphere({rng.next_1d(), rng.next_1d()}) * 5.f;
            ray.d = normalize(square_to_uniform_sphere({rng.next_1d(), rng.next_1d()}) * 0.5f - ray.o);
            SurfaceHit hit;
            if (!scene->intersect(ray, hit)) continue;
            ++hits;
            ASSERT_EQ(hit.ns, hit.ng) << "shape type " << int(type);
        }
        EXPECT_GT(hits, 500);
    }
}

// A mesh from a file keeps its vertex normals: its hits still interpolate them.
TEST(FlatPrimitives, MeshFilesKeepTheirVertexNormals) {
    test::TempDir dir;
    dir.write("tri.obj", "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nvn 0.3 0 1\nvn -0.3 0 1\nvn 0 0.3 1\nf 1//1 2//2 3//3\n");
    auto p = dir.write("s.yaml",
                       "omega: 1\n"
                       "sensor: {type: perspective, fov: 40, film: {width: 4, height: 4},\n"
                       "         to_world: {look_at: {origin: [0, 0, 5], target: [0, 0, 0], up: [0, 1, 0]}}}\n"
                       "materials: {white: {type: diffuse, reflectance: [0.5, 0.5, 0.5]}}\n"
                       "shapes:\n  - {type: mesh, file: tri.obj, material: white}\n");
    auto scene = Scene::build(parse_scene_file(p.string()));
    Ray ray;
    ray.o = {0.1f, -0.2f, 5};
    ray.d = {0, 0, -1};
    SurfaceHit hit;
    ASSERT_TRUE(scene->intersect(ray, hit));
    EXPECT_NE(hit.ns, hit.ng);
    EXPECT_GT(std::abs(hit.ns.x), 0.01f);
}

}  // namespace
}  // namespace omega
