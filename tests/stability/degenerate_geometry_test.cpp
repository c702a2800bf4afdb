// A camera inside a closed mesh, lights facing away, and zero-area triangles.
// - Inside a closed triangle mesh (an OBJ cube, 12 triangles, shared vertices) of albedo rho
//   emitting Le on both sides, every pixel is Le / (1 - rho), for every integrator: leaks at
//   edges and corners would lose energy.
// - The same mesh with zero-area triangles (a repeated vertex, three collinear vertices) is an
//   error by default; with drop_degenerate they are skipped and the furnace is unchanged.
// - One-sided lights that face away from everything leave the image exactly black; the same
//   mesh turned inside out (flip_normals) lights the interior again.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "scene/scene_error.h"
#include "scene/test_helpers.h"
#include "stability_util.h"

namespace omega {
namespace {

// Each test writes into its own folder: ctest runs the path/light/bdpt instances of one test at
// once, and a shared file name let one truncate the mesh another was loading.
std::string write_cube_obj(const test::TempDir& dir, bool with_degenerate) {
    std::ostringstream f;
    f << "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n";
    if (with_degenerate) f << "v 0 -1 -1\n";  // 9: the midpoint of edge 1-2
    // Outward winding.
    f << "f 1 4 3\nf 1 3 2\n"   // z = -1
         "f 5 6 7\nf 5 7 8\n"   // z = +1
         "f 1 2 6\nf 1 6 5\n"   // y = -1
         "f 4 8 7\nf 4 7 3\n"   // y = +1
         "f 1 5 8\nf 1 8 4\n"   // x = -1
         "f 2 3 7\nf 2 7 6\n";  // x = +1
    if (with_degenerate) f << "f 1 1 3\nf 1 9 2\nf 7 7 7\n";
    return dir.write(with_degenerate ? "cube_degenerate.obj" : "cube.obj", f.str()).string();
}

SceneDesc mesh_furnace(const std::string& file, IntegratorType type, float rho, float le, bool two_sided) {
    SceneDesc d = test::empty_scene(8, 8);
    d.integrator.type = type;
    d.integrator.max_depth = -1;
    d.sensor.to_world = Mat4::translate({0.1, -0.2, 0.15});  // off-centre: rays meet edges at all angles
    d.sensor.fov = 100;
    d.materials["wall"] = test::diffuse("wall", Rgb(rho));
    ShapeDesc s;
    s.type = ShapeType::Mesh;
    s.file = file;
    s.material = "wall";
    s.emitter = EmitterDesc{Rgb(le), two_sided};
    d.shapes.push_back(s);
    return d;
}

long long spp_for(IntegratorType t) { return t == IntegratorType::Path ? 64 : 32; }

class ClosedMesh : public ::testing::TestWithParam<IntegratorType> {};

TEST_P(ClosedMesh, CameraInsideSeesTheFurnace) {
    const float rho = 0.8f, le = 0.5f;
    const double expected = double(le) / (1.0 - double(rho));
    const test::TempDir tmp;
    for (bool degenerate : {false, true}) {
        SceneDesc d = mesh_furnace(write_cube_obj(tmp, degenerate), GetParam(), rho, le, true);
        d.shapes[0].drop_degenerate = degenerate;
        auto r = test::render(d, spp_for(GetParam()), 71);
        stability::expect_finite(r, "closed mesh");
        double z = stability::z_with_slack(r.film(), expected);
        EXPECT_LT(z, test::z_threshold(3 * 2 + 3)) << stability::name_of(GetParam()) << (degenerate ? " dropped" : "")
                                                   << " mean " << r.report.error.image_mean << " expected " << expected;
        std::printf("[ stability ] %s camera inside closed mesh%s: mean %.6g expected %.6g, z %.2f, %.2f s\n",
                    stability::name_of(GetParam()), degenerate ? " (degenerates dropped)" : "",
                    r.report.error.image_mean, expected, z, r.report.elapsed_s);
    }
}

// A one-sided emitter facing outward lights nothing inside; flipped, it lights the interior.
TEST_P(ClosedMesh, LightFacingAwayIsDarkFlippedIsNot) {
    const float rho = 0.8f, le = 0.5f;
    const test::TempDir tmp;
    SceneDesc d = mesh_furnace(write_cube_obj(tmp, false), GetParam(), rho, le, false);
    auto r = test::render(d, spp_for(GetParam()), 72);
    stability::expect_finite(r, "facing away");
    double expected = double(le) / (1.0 - double(rho));
    // Not exactly 0 for path and bdpt: next-event samples on the face the shading point lies on
    // see the emitter at cos ~ 0 whose rounded sign is sometimes positive ("front"); their
    // contribution is weighted by that cosine (measured: image mean 1e-14 to 2e-14 of 2.5).
    // Bounded at 1e-9 of the lit value: any real leak is orders of magnitude above.
    EXPECT_LT(r.report.error.image_mean, 1e-9 * expected) << stability::name_of(GetParam());
    std::printf("[ stability ] %s camera inside mesh, emitter facing out: image mean %.3g\n",
                stability::name_of(GetParam()), r.report.error.image_mean);
    d.shapes[0].flip_normals = true;
    auto f = test::render(d, spp_for(GetParam()), 73);
    stability::expect_finite(f, "flipped");
    EXPECT_LT(stability::z_with_slack(f.film(), expected), test::z_threshold(3 * 2 + 3))
        << stability::name_of(GetParam()) << " mean " << f.report.error.image_mean;
}

INSTANTIATE_TEST_SUITE_P(Integrators, ClosedMesh,
                         ::testing::Values(IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt),
                         [](const auto& info) { return std::string(stability::name_of(info.param)); });

// Exported meshes routinely hold zero-area triangles: by default they are dropped and counted in
// one warning naming the shape and the file; drop_degenerate: false restores the strict error.
TEST(ZeroAreaTriangles, AreDroppedWithOneWarningByDefault) {
    const test::TempDir tmp;
    SceneDesc d = mesh_furnace(write_cube_obj(tmp, true), IntegratorType::Path, 0.8f, 0.5f, true);
    d.shapes[0].name = "DoorHandle";
    d.shapes[0].written = "door.obj";
    ASSERT_TRUE(d.shapes[0].drop_degenerate);
    auto scene = Scene::build(d);
    ASSERT_EQ(scene->warnings().size(), 1u);
    const std::string& w = scene->warnings()[0];
    EXPECT_NE(w.find("shapes[0] 'DoorHandle' (door.obj): 3 degenerate (zero-area) triangles dropped"), std::string::npos)
        << w;
    EXPECT_EQ(scene->shapes()[0].mesh.triangle_count(), 12u);

    d.shapes[0].drop_degenerate = false;
    try {
        Scene::build(d);
        ADD_FAILURE() << "a mesh with zero-area triangles was accepted with drop_degenerate: false";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("triangle 12 is degenerate"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("door.obj"), std::string::npos) << e.what();
    }
}

// A NaN or infinite vertex would render a wrong image: always an error naming the file and the
// first triangle that uses it. One no triangle uses is harmless.
TEST(NonFiniteVertices, AreAnErrorNamingFileAndTriangle) {
    const test::TempDir tmp;
    const std::string path = tmp.write("nan_vertex.obj",
                                       "v 0 0 0\nv 1 0 0\nv 0 1 0\nv nan 1 1\nv 1 inf 1\n"
                                       "f 1 2 3\nf 1 3 2\nf 2 4 3\n")
                                 .string();
    SceneDesc d = mesh_furnace(path, IntegratorType::Path, 0.8f, 0.5f, true);
    d.shapes[0].written = "nan.obj";
    for (bool drop : {true, false}) {
        d.shapes[0].drop_degenerate = drop;
        try {
            Scene::build(d);
            ADD_FAILURE() << "a NaN vertex was accepted";
        } catch (const SceneError& e) {
            EXPECT_NE(std::string(e.what()).find("(nan.obj) triangle 2 has a non-finite vertex (vertex 3)"),
                      std::string::npos)
                << e.what();
        }
    }
}

// Open scene: a floor, and a one-sided rectangular light above it facing up (away from the floor,
// with nothing above). A camera under the light, looking down, sees the floor: all black.
TEST(LightsFacingAway, OpenSceneIsBlack) {
    for (IntegratorType t : {IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt}) {
        SceneDesc d = test::empty_scene(8, 8);
        d.integrator.type = t;
        // Between the floor and the light, looking down: sees the floor, and the light's back
        // only through the edge of its field of view.
        d.sensor.to_world = Mat4::look_at({0, 0, 0.5}, {0, 0, 0}, {0, 1, 0});
        d.sensor.fov = 120;
        d.materials["floor"] = test::diffuse("floor", Rgb(0.8f));
        ShapeDesc floor;
        floor.type = ShapeType::Rectangle;
        floor.to_world = Mat4::scale({4, 4, 1});
        floor.material = "floor";
        d.shapes.push_back(floor);
        ShapeDesc light;
        light.type = ShapeType::Rectangle;
        light.to_world = Mat4::translate({0, 0, 1}) * Mat4::scale({0.5, 0.5, 1});  // faces +z: away from the floor
        light.material = "floor";
        light.emitter = EmitterDesc{Rgb(10.f), false};
        d.shapes.push_back(light);
        auto r = test::render(d, 16, 74);
        stability::expect_finite(r, "open facing away");
        // The test can fail: the same light facing down lights the floor.
        d.shapes[1].flip_normals = true;
        auto lit = test::render(d, 16, 75);
        EXPECT_GT(lit.report.error.image_mean, 0.0) << stability::name_of(t);
        // Black up to the coplanar rounding described above (next-event samples on the emitter's
        // own plane, from its diffuse back): measured ~1e-14 of the lit image for path.
        EXPECT_LT(r.report.error.image_mean, 1e-9 * lit.report.error.image_mean) << stability::name_of(t);
        std::printf("[ stability ] %s open scene, light facing away: image mean %.3g (lit: %.3g)\n",
                    stability::name_of(t), r.report.error.image_mean, lit.report.error.image_mean);
    }
}

TEST(ClosedMeshSanity, DetectsALeak) {
    // A mesh furnace with one face missing leaks energy: caught against the closed form.
    const test::TempDir tmp;
    const std::string path =
        tmp.write("cube_open.obj",
                  "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
                  "f 1 4 3\nf 1 3 2\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n")
            .string();
    auto r = test::render(mesh_furnace(path, IntegratorType::Path, 0.8f, 0.5f, true), 64, 76);
    EXPECT_GT(stability::z_with_slack(r.film(), 0.5 / (1.0 - 0.8)), test::z_threshold(1));
}

}  // namespace
}  // namespace omega
