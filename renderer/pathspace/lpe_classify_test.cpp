// Warnings for AOV expressions that can only render black, with the classifier's reasoning
// (Veach, Theorem 8.3).
#include <gtest/gtest.h>

#include "pathspace/lpe_classify.h"
#include "render_harness.h"

namespace omega {
namespace {

// A diffuse floor and a mirror seen by a pinhole camera, lit by a point light or an area light.
std::unique_ptr<Scene> mirror_scene(bool area_light, bool glossy = false) {
    SceneDesc d = test::empty_scene(8, 8);
    d.materials["white"] = test::diffuse("white", Rgb(0.5f));
    d.materials["mirror"] = MaterialDesc{"mirror", ConductorBsdf{}, {}};
    ShapeDesc floor;
    floor.type = ShapeType::Rectangle;
    floor.to_world = Mat4::translate({0, 0, 3});
    floor.material = "white";
    d.shapes.push_back(floor);
    ShapeDesc m = floor;
    m.to_world = Mat4::translate({1, 0, 2});
    m.material = "mirror";
    d.shapes.push_back(m);
    if (glossy) {
        ConductorBsdf rough;
        rough.alpha_u = rough.alpha_v = 0.1f;
        d.materials["rough"] = MaterialDesc{"rough", rough, {}};
        ShapeDesc r = floor;
        r.to_world = Mat4::translate({-1, 0, 2});
        r.material = "rough";
        d.shapes.push_back(r);
    }
    if (area_light) {
        ShapeDesc l = floor;
        l.to_world = Mat4::translate({0, 2, 2});
        l.emitter = EmitterDesc{Rgb(1.f), true};
        d.shapes.push_back(l);
    } else {
        LightDesc l;
        l.type = LightType::Point;
        l.position = {0, 1, 1};
        d.lights.push_back(l);
    }
    return Scene::build(d);
}

std::vector<std::string> warn(const Scene& s, const char* expr, IntegratorType t) {
    return aov_warnings(s, LpeSet(std::vector<AovDesc>{{"x", expr}}), t);
}

TEST(LpeWarnings, PointLightInAMirrorIsTheorem83) {
    auto s = mirror_scene(false);
    for (IntegratorType t : {IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt}) {
        auto w = warn(*s, "L S E", t);
        ASSERT_EQ(w.size(), 1u);
        EXPECT_NE(w[0].find("Theorem 8.3"), std::string::npos) << w[0];
        EXPECT_NE(w[0].find("L S D S D S E"), std::string::npos) << w[0];
        EXPECT_NE(w[0].find("aov x (L S E)"), std::string::npos) << w[0];
        // Direct light, and light on the floor seen in the mirror (L S D D S S E... sampled by
        // next-event estimation from the floor), are fine for every integrator that has them.
        EXPECT_TRUE(warn(*s, "L D E", t).empty()) << int(t);
        EXPECT_TRUE(warn(*s, "L .* S .* E", t).empty());  // L D S E: the floor in the mirror
    }
    // Seen in the mirror, the floor: the path tracer's next-event estimation reaches it (L D S E),
    // the light tracer cannot (its last vertex before the pinhole is S).
    EXPECT_TRUE(warn(*s, "L D S E", IntegratorType::Path).empty());
    auto wl = warn(*s, "L D S E", IntegratorType::Light);
    ASSERT_EQ(wl.size(), 1u);
    EXPECT_NE(wl[0].find("the light tracer cannot"), std::string::npos) << wl[0];
}

TEST(LpeWarnings, AreaLightInAMirrorIsSampleable) {
    // L D D S D S E: the camera subpath hits the light through the mirror (s = 0).
    auto s = mirror_scene(true);
    EXPECT_TRUE(warn(*s, "L S E", IntegratorType::Path).empty());
    EXPECT_TRUE(warn(*s, "L S E", IntegratorType::Bdpt).empty());
    EXPECT_EQ(warn(*s, "L S E", IntegratorType::Light).size(), 1u);
}

TEST(LpeWarnings, ClassTheSceneLacks) {
    auto s = mirror_scene(true);
    auto w = warn(*s, "L .* G .* E", IntegratorType::Bdpt);
    ASSERT_EQ(w.size(), 1u);
    EXPECT_NE(w[0].find("no path this scene can produce"), std::string::npos) << w[0];
    EXPECT_NE(w[0].find("S, D"), std::string::npos) << w[0];
    // The expression itself can match nothing: E before L.
    EXPECT_EQ(warn(*s, "E .* L", IntegratorType::Bdpt).size(), 1u);
    // With a rough conductor in the scene, G exists and D alone still covers it.
    auto g = mirror_scene(true, true);
    EXPECT_TRUE(warn(*g, "L .* G .* E", IntegratorType::Bdpt).empty());
    EXPECT_TRUE(warn(*g, "L D+ E", IntegratorType::Bdpt).empty());
}

TEST(LpeWarnings, BoundedRepetition) {
    // Up to three mirror bounces between a point light and a pinhole: never a DD edge.
    auto s = mirror_scene(false);
    EXPECT_EQ(warn(*s, "L S{1,3} E", IntegratorType::Bdpt).size(), 1u);
    // One more D anywhere and light tracing or next-event estimation reaches it.
    EXPECT_TRUE(warn(*s, "L S{0,3} D S{0,3} E", IntegratorType::Bdpt).empty());
}

}  // namespace
}  // namespace omega
