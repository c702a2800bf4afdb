#include "scene/param_bag.h"

#include <gtest/gtest.h>

#include "scene/test_helpers.h"

using namespace omega;
using omega::test::scene_error_of;

namespace {

ParamBag bag_of(const std::string& yaml, const std::string& path = "") {
    return ParamBag(ParamValue(YAML::Load(yaml), path, std::make_shared<const std::string>("t.yaml"), 1));
}

}  // namespace

TEST(ParamBag, TypedGettersAndDefaults) {
    ParamBag b = bag_of("f: 1.5\ni: -3\nb: true\ns: hello\nc: [0.1, 0.2, 0.3]\ng: 0.5\nv: [1, 2, 3]\ne: tent\n"
                        "n: {x: 2}\nl: [1, 2]\n");
    EXPECT_FLOAT_EQ(b.get_float("f", 0), 1.5f);
    EXPECT_EQ(b.get_int("i", 0), -3);
    EXPECT_TRUE(b.get_bool("b", false));
    EXPECT_EQ(b.get_string("s", ""), "hello");
    EXPECT_EQ(b.get_rgb("c", {}), (Rgb{0.1f, 0.2f, 0.3f}));
    EXPECT_EQ(b.get_rgb("g", {}), (Rgb{0.5f, 0.5f, 0.5f}));
    EXPECT_EQ(b.get_vec3("v", {}), (Vec3d{1, 2, 3}));
    EXPECT_EQ(b.get_enum<int>("e", {{"box", 0}, {"tent", 1}}, 0), 1);
    ParamBag n = b.bag("n");
    EXPECT_EQ(n.get_int("x", 0), 2);
    n.check_unused();
    EXPECT_EQ(b.list("l").size(), 2u);
    // Defaults for absent keys.
    EXPECT_EQ(b.get_float("absent", 7.f), 7.f);
    EXPECT_EQ(b.get_string("absent2", "d"), "d");
    EXPECT_NO_THROW(b.check_unused());
}

TEST(ParamBag, UnusedKeysAreReportedWithLineAndPath) {
    ParamBag b = bag_of("a: 1\nreflectanse: 2\nc: 3\n", "materials.white");
    b.get_int("a", 0);
    EXPECT_EQ(b.unused_messages().size(), 2u);
    EXPECT_EQ(scene_error_of([&] { b.check_unused(); }),
              "t.yaml:2: materials.white.reflectanse: unknown key\nt.yaml:3: materials.white.c: unknown key");
}

TEST(ParamBag, WrongTypesNameFileLineAndKey) {
    ParamBag b = bag_of("x: 1\nsensor: {fov: abc, q: \"45\", l: [1, 2], m: {a: 1}, n: , big: 1e999, "
                        "nan: .nan, inf: -.inf, f: 1e300, i: 2.5, ii: 99999999999999999999, c: [1, x, 2], e: boxx}\n");
    ParamBag s = b.bag("sensor");
    EXPECT_EQ(scene_error_of([&] { s.get_float("fov", 0); }), "t.yaml:2: sensor.fov: expected a number, got 'abc'");
    EXPECT_EQ(scene_error_of([&] { s.get_float("q", 0); }), "t.yaml:2: sensor.q: expected a number, got '45'");
    EXPECT_EQ(scene_error_of([&] { s.get_float("l", 0); }), "t.yaml:2: sensor.l: expected a number, got a list");
    EXPECT_EQ(scene_error_of([&] { s.get_string("m", ""); }), "t.yaml:2: sensor.m: expected a string, got a mapping");
    EXPECT_EQ(scene_error_of([&] { s.get_float("n", 0); }), "t.yaml:2: sensor.n: expected a number, got nothing");
    EXPECT_EQ(scene_error_of([&] { s.get_double("big", 0); }), "t.yaml:2: sensor.big: number out of range: '1e999'");
    EXPECT_EQ(scene_error_of([&] { s.get_double("nan", 0); }),
              "t.yaml:2: sensor.nan: expected a finite number, got '.nan'");
    EXPECT_EQ(scene_error_of([&] { s.get_double("inf", 0); }),
              "t.yaml:2: sensor.inf: expected a finite number, got '-.inf'");
    EXPECT_EQ(scene_error_of([&] { s.get_float("f", 0); }), "t.yaml:2: sensor.f: number out of range: '1e300'");
    EXPECT_EQ(scene_error_of([&] { s.get_int("i", 0); }), "t.yaml:2: sensor.i: expected an integer, got '2.5'");
    EXPECT_EQ(scene_error_of([&] { s.get_int("ii", 0); }),
              "t.yaml:2: sensor.ii: integer out of range: '99999999999999999999'");
    EXPECT_EQ(scene_error_of([&] { s.get_rgb("c", {}); }), "t.yaml:2: sensor.c[1]: expected a number, got 'x'");
    EXPECT_EQ(scene_error_of([&] { s.get_enum<int>("e", {{"box", 0}, {"tent", 1}}, 0); }),
              "t.yaml:2: sensor.e: expected one of box, tent, got 'boxx'");
    EXPECT_EQ(scene_error_of([&] { b.get_int("x", 0, 2, 5); }), "t.yaml:1: x: must be in [2, 5], got 1");
    EXPECT_EQ(scene_error_of([&] { b.bag("x"); }), "t.yaml:1: x: expected a mapping, got '1'");
    EXPECT_EQ(scene_error_of([&] { b.require("missing"); }), "t.yaml:1: missing: missing key");
}

TEST(ParamBag, NotAMappingOrDuplicateKeys) {
    EXPECT_EQ(scene_error_of([] { bag_of("[1, 2]"); }), "t.yaml:1: expected a mapping, got a list");
    EXPECT_EQ(scene_error_of([] { bag_of("a: 1\na: 2\n", "p"); }), "t.yaml:2: p.a: duplicate key");
    EXPECT_EQ(scene_error_of([] { bag_of("? [1]\n: 2\n"); }), "t.yaml:1: keys must be plain strings");
}
