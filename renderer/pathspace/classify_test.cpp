// Veach's tables 8.1 and 8.2 as unit tests of the full-path classifier, plus the integrator-
// specific verdicts and the warnings a user sees.
#include <gtest/gtest.h>

#include "pathspace/classify.h"
#include "render_harness.h"

namespace omega {
namespace {

EndpointClass E(const char* two) { return {two[0], two[1]}; }
// Sensor classes are written as in the table (direction, then position): "DS" is a pinhole.
EndpointClass sensor_from_table(const char* yx) { return {yx[1], yx[0]}; }

TEST(Classifier, Table81Emitters) {
    EXPECT_EQ(classify_light(AreaLight{}).position, 'D');
    EXPECT_EQ(classify_light(AreaLight{}).direction, 'D');  // LDD: a diffusely emitting sphere
    EXPECT_EQ(classify_light(PointLight{}).position, 'S');  // LSD: a point spotlight
    EXPECT_EQ(classify_light(PointLight{}).direction, 'D');
    EXPECT_EQ(classify_light(SpotLight{}).position, 'S');
    EXPECT_EQ(classify_light(DirectionalLight{}).position, 'D');  // LDS: sunlight through a window
    EXPECT_EQ(classify_light(DirectionalLight{}).direction, 'S');
    EXPECT_EQ(classify_light(ConstantLight{}).direction, 'D');
    // An envmap is an area at infinity, like the constant environment: LDD.
    EXPECT_EQ(classify_light(EnvMapLight{}).position, 'D');
    EXPECT_EQ(classify_light(EnvMapLight{}).direction, 'D');
}

TEST(Classifier, Table81Sensors) {
    SensorDesc d;
    d.type = SensorType::Perspective;
    Sensor pin = Sensor::from_desc(d);
    EXPECT_EQ(classify_sensor(pin).direction, 'D');  // DSE: a pinhole lens
    EXPECT_EQ(classify_sensor(pin).position, 'S');
    d.type = SensorType::ThinLens;
    d.aperture_radius = 0.1f;
    Sensor lens = Sensor::from_desc(d);
    EXPECT_EQ(classify_sensor(lens).direction, 'D');  // DDE: a finite-aperture lens
    EXPECT_EQ(classify_sensor(lens).position, 'D');
    d.type = SensorType::Orthographic;
    Sensor ortho = Sensor::from_desc(d);
    EXPECT_EQ(classify_sensor(ortho).direction, 'S');  // SDE: an orthographic projection lens
    EXPECT_EQ(classify_sensor(ortho).position, 'D');
}

TEST(Classifier, Table82UnsampleablePaths) {
    // L S D S D S E: a point light source reflected in a mirror, viewed with a pinhole lens.
    PathClass a{E("SD"), "S", sensor_from_table("DS")};
    EXPECT_EQ(a.regex(), "L S D S D S E");
    EXPECT_FALSE(locally_sampleable(a));
    // L D S S D S D E: caustics from a parallel light source, viewed with an orthographic lens.
    PathClass b{E("DS"), "SD", sensor_from_table("SD")};
    EXPECT_EQ(b.regex(), "L D S S D S D E");
    EXPECT_FALSE(locally_sampleable(b));
    // L S D S D S D S E: caustics from a point light, viewed indirectly through a mirror (pinhole).
    PathClass c{E("SD"), "SDS", sensor_from_table("DS")};
    EXPECT_EQ(c.regex(), "L S D S D S D S E");
    EXPECT_FALSE(locally_sampleable(c));
    // None of them by any of our integrators either.
    for (IntegratorType t : {IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt}) {
        EXPECT_FALSE(sampleable_by(a, t));
        EXPECT_FALSE(sampleable_by(c, t));
    }
}

TEST(Classifier, SampleablePaths) {
    // Caustics from a point light seen directly: L S D S D D S E has DD, BDPT (t = 1) samples it.
    PathClass caustic{E("SD"), "SD", sensor_from_table("DS")};
    EXPECT_TRUE(locally_sampleable(caustic));
    EXPECT_TRUE(sampleable_by(caustic, IntegratorType::Bdpt));
    EXPECT_TRUE(sampleable_by(caustic, IntegratorType::Light));
    EXPECT_FALSE(sampleable_by(caustic, IntegratorType::Path));
    // The same caustic from an area light: the path tracer hits the light (s = 0).
    PathClass area_caustic{E("DD"), "SD", sensor_from_table("DS")};
    EXPECT_TRUE(sampleable_by(area_caustic, IntegratorType::Path));
    // A mirror seen by a pinhole: light tracing cannot end on S before a delta sensor position... it needs a D last vertex.
    PathClass mirror{E("DD"), "DS", sensor_from_table("DS")};
    EXPECT_TRUE(sampleable_by(mirror, IntegratorType::Path));
    EXPECT_FALSE(sampleable_by(mirror, IntegratorType::Light));
    // Every path of a finite-aperture lens or of an area light is locally sampleable.
    for (const char* seq : {"", "S", "SS", "SDS", "D", "DSD"}) {
        EXPECT_TRUE(locally_sampleable(PathClass{E("SD"), seq, sensor_from_table("DD")})) << seq;
        EXPECT_TRUE(locally_sampleable(PathClass{E("DD"), seq, sensor_from_table("DS")})) << seq;
    }
}

SceneDesc scene_with(LightType light, SensorType sensor, bool mirror, bool area) {
    SceneDesc d = test::empty_scene(8, 8);
    d.sensor.type = sensor;
    if (sensor == SensorType::ThinLens) d.sensor.aperture_radius = 0.1f;
    d.materials["white"] = test::diffuse("white", Rgb(0.5f));
    d.materials["mirror"] = MaterialDesc{"mirror", ConductorBsdf{}, {}};
    ShapeDesc floor;
    floor.type = ShapeType::Rectangle;
    floor.to_world = Mat4::translate({0, 0, 3});
    floor.material = "white";
    d.shapes.push_back(floor);
    if (mirror) {
        ShapeDesc m = floor;
        m.to_world = Mat4::translate({1, 0, 2});
        m.material = "mirror";
        d.shapes.push_back(m);
    }
    if (area) {
        ShapeDesc l = floor;
        l.to_world = Mat4::translate({0, 2, 2});
        l.emitter = EmitterDesc{Rgb(1.f), true};
        d.shapes.push_back(l);
    } else {
        LightDesc l;
        l.type = light;
        l.position = {0, 1, 1};
        d.lights.push_back(l);
    }
    return d;
}

TEST(Classifier, WarningsNameMissingClasses) {
    auto scene = Scene::build(scene_with(LightType::Point, SensorType::Perspective, true, false));
    auto w = path_space_warnings(*scene, IntegratorType::Bdpt);
    ASSERT_FALSE(w.empty());
    // The mirror is planar: the connector reaches the point light seen in it once (L S D S D S
    // E), not seen in it twice.
    EXPECT_EQ(w[0].rfind("L S D S S D S E (", 0), 0u) << w[0];
    EXPECT_NE(w[0].find("Theorem 8.3"), std::string::npos) << w[0];
    for (const auto& s : w) EXPECT_EQ(s.rfind("L S D S D S E (", 0), std::string::npos) << s;
    // The path tracer also misses the point light seen directly and caustics seen directly.
    auto wp = path_space_warnings(*scene, IntegratorType::Path);
    bool direct = false;
    for (const auto& s : wp) direct |= s.rfind("L S D D S E (", 0) == 0;
    EXPECT_TRUE(direct);
}

TEST(Classifier, NoWarningsForAreaLightsLensesOrNoSpecular) {
    // Only area lights.
    auto a = Scene::build(scene_with(LightType::Point, SensorType::Perspective, true, true));
    EXPECT_TRUE(path_space_warnings(*a, IntegratorType::Bdpt).empty());
    EXPECT_TRUE(path_space_warnings(*a, IntegratorType::Path).empty());
    // A finite-aperture lens with a point light and a mirror: every class is locally sampleable,
    // and BDPT samples L S D S D D E (the point light seen in the mirror) by t = 0, light
    // subpaths that hit the lens.
    auto b = Scene::build(scene_with(LightType::Point, SensorType::ThinLens, true, false));
    EXPECT_TRUE(path_space_warnings(*b, IntegratorType::Bdpt).empty());
    EXPECT_TRUE(plan_strategies(*b).t0);
    // The path and light tracers still miss it, and say that bdpt can sample it.
    for (IntegratorType it : {IntegratorType::Path, IntegratorType::Light}) {
        auto w = path_space_warnings(*b, it);
        bool named = false;
        for (const auto& s : w) {
            EXPECT_EQ(s.find("Theorem 8.3"), std::string::npos) << s;
            named |= s.rfind("L S D S D D E (", 0) == 0 && s.find("(bdpt can)") != std::string::npos;
        }
        EXPECT_TRUE(named);
    }
    // A pinhole cannot be hit: no t = 0.
    EXPECT_FALSE(plan_strategies(*Scene::build(scene_with(LightType::Point, SensorType::Perspective, true, false))).t0);
    // No specular surface.
    auto c = Scene::build(scene_with(LightType::Point, SensorType::Perspective, false, false));
    EXPECT_TRUE(path_space_warnings(*c, IntegratorType::Bdpt).empty());
}

TEST(Classifier, PlanSkipsStrategiesThatCannotContribute) {
    auto point = Scene::build(scene_with(LightType::Point, SensorType::Perspective, false, false));
    EXPECT_FALSE(plan_strategies(*point).s0);  // no light can be hit
    EXPECT_TRUE(plan_strategies(*point).connections);
    SceneDesc d = scene_with(LightType::Point, SensorType::Perspective, true, true);
    d.shapes[0].material = "mirror";
    d.shapes.back().material = "mirror";  // every surface specular: nothing to connect to
    auto specular = Scene::build(d);
    EXPECT_TRUE(plan_strategies(*specular).s0);
    EXPECT_FALSE(plan_strategies(*specular).connections);
    EXPECT_FALSE(plan_strategies(*specular).light_subpaths);
}

}  // namespace
}  // namespace omega
