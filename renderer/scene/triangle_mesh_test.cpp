#include "io/file_gate.h"
#include "scene/triangle_mesh.h"

#include <gtest/gtest.h>

#include <cstring>

#include "scene/scene_parser.h"
#include "scene/test_helpers.h"

using namespace omega;
using omega::test::scene_error_of;
using omega::test::TempDir;

namespace {

Vec3d geometric_normal(const TriangleMesh& m, size_t t) {
    Vec3d a(m.positions[m.indices[3 * t]]), b(m.positions[m.indices[3 * t + 1]]), c(m.positions[m.indices[3 * t + 2]]);
    return normalize(cross(b - a, c - a));
}

Transform xf(const Mat4& m) { return *Transform::make(m); }

}  // namespace

TEST(TriangleMesh, Rectangle) {
    TriangleMesh m = make_rectangle();
    EXPECT_EQ(m.positions.size(), 4u);
    ASSERT_EQ(m.triangle_count(), 2u);
    for (size_t t = 0; t < 2; ++t) EXPECT_NEAR(geometric_normal(m, t).z, 1, 1e-12);
    for (auto& p : m.positions) EXPECT_TRUE(std::abs(p.x) == 1 && std::abs(p.y) == 1 && p.z == 0);
}

TEST(TriangleMesh, CubeHasSharpOutwardFaces) {
    TriangleMesh m = make_cube();
    EXPECT_EQ(m.positions.size(), 24u);
    EXPECT_EQ(m.normals.size(), 24u);
    ASSERT_EQ(m.triangle_count(), 12u);
    for (size_t t = 0; t < 12; ++t) {
        Vec3d n = geometric_normal(m, t);
        Vec3d centroid{0, 0, 0};
        for (int k = 0; k < 3; ++k) {
            uint32_t i = m.indices[3 * t + size_t(k)];
            centroid += Vec3d(m.positions[i]) / 3.0;
            EXPECT_EQ(Vec3d(m.normals[i]), n);  // vertex normals equal the face normal
        }
        EXPECT_NEAR(dot(n, centroid), 1, 1e-12);  // outward, on the face at distance 1
    }
}

TEST(TriangleMesh, Disk) {
    TriangleMesh m = make_disk(16);
    EXPECT_EQ(m.triangle_count(), 16u);
    double area = 0;
    for (size_t t = 0; t < 16; ++t) {
        EXPECT_NEAR(geometric_normal(m, t).z, 1, 1e-6);
        Vec3d a(m.positions[m.indices[3 * t]]), b(m.positions[m.indices[3 * t + 1]]), c(m.positions[m.indices[3 * t + 2]]);
        area += 0.5 * length(cross(b - a, c - a));
    }
    EXPECT_NEAR(area, 0.5 * 16 * std::sin(2 * kPiD / 16), 1e-5);
}

TEST(TriangleMesh, BakeTransformsAndFlips) {
    TriangleMesh m = make_rectangle();
    size_t dropped = bake_mesh(m, xf(Mat4::translate({0, 0, 2}) * Mat4::scale({2, 1, 1})), false, false, {}, "rect");
    EXPECT_EQ(dropped, 0u);
    EXPECT_EQ(m.positions[2], (Vec3{2, 1, 2}));
    EXPECT_NEAR(geometric_normal(m, 0).z, 1, 1e-12);
    EXPECT_EQ(m.normals[0], (Vec3{0, 0, 1}));

    // A mirror keeps the winding consistent with the transformed normal.
    TriangleMesh r = make_rectangle();
    bake_mesh(r, xf(Mat4::scale({1, 1, -1})), false, false, {}, "rect");
    EXPECT_EQ(r.normals[0], (Vec3{0, 0, -1}));
    EXPECT_NEAR(geometric_normal(r, 0).z, -1, 1e-12);

    TriangleMesh f = make_rectangle();
    bake_mesh(f, xf(Mat4::identity()), true, false, {}, "rect");
    EXPECT_EQ(f.normals[0], (Vec3{0, 0, -1}));
    EXPECT_NEAR(geometric_normal(f, 0).z, -1, 1e-12);

    // Normals go through the inverse transpose: a 45° plane stretched in x.
    TriangleMesh s;
    s.positions = {{0, 0, 0}, {1, 0, 1}, {0, 1, 0}};
    s.normals.assign(3, normalize(Vec3{-1, 0, 1}));
    s.indices = {0, 1, 2};
    bake_mesh(s, xf(Mat4::scale({2, 1, 1})), false, false, {}, "s");
    Vec3 expect = normalize(Vec3{-0.5f, 0, 1});
    EXPECT_NEAR(s.normals[0].x, expect.x, 1e-6);
    EXPECT_NEAR(s.normals[0].z, expect.z, 1e-6);
    EXPECT_NEAR(dot(Vec3(geometric_normal(s, 0)), expect), 1, 1e-6);
}

TEST(TriangleMesh, LoadObj) {
    TempDir dir;
    // Two quads (triangulated to four triangles) sharing an edge, placed in z = 0 and x = 1.
    auto p = dir.write("quads.obj",
                       "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 0 -1\nv 1 1 -1\n"
                       "f 1 2 3 4\nf 2 5 6 3\n");
    TriangleMesh m = load_mesh_file(*FileGate::unconfined(), p.string(), {});
    EXPECT_EQ(m.triangle_count(), 4u);
    EXPECT_TRUE(m.normals.empty());  // the file has none and none are made up
    bake_mesh(m, xf(Mat4::translate({10, 0, 0})), false, false, {}, "quads");
    float min_x = 1e9f, max_x = -1e9f;
    for (auto& v : m.positions) min_x = std::min(min_x, v.x), max_x = std::max(max_x, v.x);
    EXPECT_EQ(min_x, 10.f);
    EXPECT_EQ(max_x, 11.f);

    auto pn = dir.write("n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n");
    TriangleMesh n = load_mesh_file(*FileGate::unconfined(), pn.string(), {});
    ASSERT_EQ(n.normals.size(), n.positions.size());
    EXPECT_EQ(n.normals[0], (Vec3{0, 0, 1}));
}

TEST(TriangleMesh, LoadPly) {
    TempDir dir;
    auto p = dir.write("m.ply",
                       "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                       "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
                       "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n4 0 1 2 3\n3 0 3 4\n");
    TriangleMesh m = load_mesh_file(*FileGate::unconfined(), p.string(), {});
    EXPECT_EQ(m.triangle_count(), 3u);
    bake_mesh(m, xf(Mat4::scale({2, 2, 2})), false, false, {}, "ply");
    bool found = false;
    for (auto& v : m.positions) found |= v == Vec3{0, 0, 2};
    EXPECT_TRUE(found);
}

TEST(TriangleMesh, LoadGltfAppliesNodeTransforms) {
    TempDir dir;
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint16_t idx[3] = {0, 1, 2};
    std::string bin(42, '\0');
    std::memcpy(bin.data(), pos, 36);
    std::memcpy(bin.data() + 36, idx, 6);
    dir.write("tri.bin", bin);
    auto p = dir.write("tri.gltf", R"({
 "asset": {"version": "2.0"},
 "scene": 0, "scenes": [{"nodes": [0, 1]}],
 "nodes": [{"mesh": 0, "translation": [0, 0, 5]}, {"mesh": 0, "scale": [3, 3, 3]}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
 "buffers": [{"uri": "tri.bin", "byteLength": 42}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
 "accessors": [
  {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
  {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
})");
    TriangleMesh m = load_mesh_file(*FileGate::unconfined(), p.string(), {});
    ASSERT_EQ(m.triangle_count(), 2u);  // one mesh, instanced by two nodes
    bake_mesh(m, xf(Mat4::identity()), false, false, {}, "gltf");
    std::vector<Vec3> first = {m.positions[m.indices[0]], m.positions[m.indices[1]], m.positions[m.indices[2]]};
    std::vector<Vec3> second = {m.positions[m.indices[3]], m.positions[m.indices[4]], m.positions[m.indices[5]]};
    EXPECT_EQ(first, (std::vector<Vec3>{{0, 0, 5}, {1, 0, 5}, {0, 1, 5}}));
    EXPECT_EQ(second, (std::vector<Vec3>{{0, 0, 0}, {3, 0, 0}, {0, 3, 0}}));
}

TEST(TriangleMesh, DegenerateTrianglesNameSceneLineShapeAndTriangle) {
    TempDir dir;
    dir.write("x.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 3 2 1\n");
    std::string path = dir.write("scene.yaml",
                                 "omega: 1\nshapes:\n  - {type: cube}\n  - {type: cube}\n"
                                 "  - type: mesh\n    file: x.obj\n")
                           .string();
    SceneDesc d = parse_scene_file(path);
    const ShapeDesc& s = d.shapes[2];
    EXPECT_EQ(s.loc.key, "shapes[2]");
    TriangleMesh m = load_mesh_file(*FileGate::unconfined(), s.file, s.loc);
    ASSERT_EQ(m.triangle_count(), 3u);
    TriangleMesh copy = m;
    EXPECT_EQ(scene_error_of([&] { bake_mesh(copy, xf(s.to_world), false, false, s.loc, "mesh 'x.obj'"); }),
              path + ":5: shapes[2]: mesh 'x.obj' triangle 1 is degenerate (zero area; drop_degenerate: true, the "
                     "default, drops such triangles)");
    EXPECT_EQ(bake_mesh(m, xf(s.to_world), false, true, s.loc, "mesh 'x.obj'"), 1u);
    EXPECT_EQ(m.triangle_count(), 2u);

    // Non-finite positions after the transform are errors too, dropped or not, naming the first
    // triangle that uses one.
    TriangleMesh big = make_rectangle();
    big.normals.clear();
    EXPECT_EQ(scene_error_of([&] { bake_mesh(big, xf(Mat4::scale({1e300, 1e300, 1e300})), false, true, s.loc, "rect"); }),
              path + ":5: shapes[2]: rect triangle 0 has a non-finite vertex (vertex 0)");
}

TEST(TriangleMesh, LoadErrors) {
    TempDir dir;
    SourceLoc loc{"scene.yaml", 9, "shapes[0]"};
    auto garbage = dir.write("bad.obj", "this is not an obj file\n");
    std::string e = scene_error_of([&] { load_mesh_file(*FileGate::unconfined(), garbage.string(), loc); });
    EXPECT_EQ(e.rfind("scene.yaml:9: shapes[0]: ", 0), 0u) << e;
    e = scene_error_of([&] { load_mesh_file(*FileGate::unconfined(), (dir.path / "missing.ply").string(), loc); });
    EXPECT_EQ(e.rfind("scene.yaml:9: shapes[0]: cannot open '", 0), 0u) << e;
    EXPECT_NE(e.find("No such file or directory"), std::string::npos) << e;
}
