#include "scene/mitsuba_importer.h"
#include "shared_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "scene/scene.h"
#include "scene/scene_parser.h"
#include "scene/scene_writer.h"
#include "scene/test_helpers.h"
#include "test_images.h"

using namespace omega;
using omega::test::scene_error_of;
using omega::test::TempDir;
using omega::test::all_warnings;
using omega::test::has_warning;

namespace {

std::string shared_scene(const std::string& name) { return test::shared_path("scenes/" + name + "/scene.xml"); }
// The shared scenes lie beside the checkout (tests/support/shared_data.h); CI fails without them.
bool have_shared() { return test::shared_available(shared_scene("cornell-box")); }

SceneDesc import(const std::string& body, const MitsubaOptions& opt = {}) {
    return import_mitsuba_string("<scene version=\"3.0.0\">\n" + body + "\n</scene>\n", "scene.xml", opt);
}
std::string import_error(const std::string& body) {
    return scene_error_of([&] { import(body); });
}

void expect_mat(const Mat4& a, const std::array<double, 16>& b, double eps = 0) {
    for (size_t i = 0; i < 16; ++i) EXPECT_NEAR(a.m[i], b[i], eps) << "element " << i;
}
void expect_rgb(const Rgb& a, float r, float g, float b) {
    EXPECT_FLOAT_EQ(a.x, r);
    EXPECT_FLOAT_EQ(a.y, g);
    EXPECT_FLOAT_EQ(a.z, b);
}

// Every field the YAML parser reads, bit for bit (locations and warnings aside).
void expect_same(const SceneDesc& a, const SceneDesc& b) {
    EXPECT_EQ(a.integrator.type, b.integrator.type);
    EXPECT_EQ(a.integrator.max_depth, b.integrator.max_depth);
    EXPECT_EQ(a.integrator.rr_depth, b.integrator.rr_depth);
    const SensorDesc &s = a.sensor, &t = b.sensor;
    EXPECT_EQ(s.type, t.type);
    EXPECT_EQ(s.fov, t.fov);
    EXPECT_EQ(s.fov_axis, t.fov_axis);
    EXPECT_EQ(s.to_world.m, t.to_world.m);
    EXPECT_EQ(s.aperture_radius, t.aperture_radius);
    EXPECT_EQ(s.focus_distance, t.focus_distance);
    EXPECT_EQ(s.near_clip, t.near_clip);
    EXPECT_EQ(s.film.width, t.film.width);
    EXPECT_EQ(s.film.height, t.film.height);
    EXPECT_EQ(s.film.filter, t.film.filter);
    EXPECT_EQ(s.film.filter_radius, t.film.filter_radius);
    EXPECT_EQ(s.film.gaussian_stddev, t.film.gaussian_stddev);
    EXPECT_EQ(s.film.crop, t.film.crop);
    EXPECT_EQ(s.film.has_crop, t.film.has_crop);
    EXPECT_EQ(s.halt.spp, t.halt.spp);
    EXPECT_EQ(s.halt.time_s, t.halt.time_s);
    EXPECT_EQ(s.halt.target_error, t.halt.target_error);
    ASSERT_EQ(a.materials.size(), b.materials.size());
    for (const auto& [name, m] : a.materials) {
        ASSERT_TRUE(b.materials.count(name)) << name;
        const Bsdf &x = m.bsdf, &y = b.materials.at(name).bsdf;
        EXPECT_EQ(m.bump_scale, b.materials.at(name).bump_scale) << name;
        const auto slots_a = m.texture_slots(), slots_b = b.materials.at(name).texture_slots();
        for (size_t i = 0; i < slots_a.size(); ++i) {
            const auto &tx = *slots_a[i], &ty = *slots_b[i];
            ASSERT_EQ(tx.has_value(), ty.has_value()) << name;
            if (tx) {
                EXPECT_EQ(tx->file, ty->file) << name;
                EXPECT_EQ(tx->filter, ty->filter) << name;
                EXPECT_EQ(tx->wrap, ty->wrap) << name;
                EXPECT_EQ(tx->raw, ty->raw) << name;
                EXPECT_EQ(tx->to_uv.m, ty->to_uv.m) << name;
                EXPECT_EQ(tx->checker, ty->checker) << name;
                EXPECT_EQ(tx->color0, ty->color0) << name;
                EXPECT_EQ(tx->color1, ty->color1) << name;
            }
        }
        EXPECT_EQ(m.opacity, b.materials.at(name).opacity) << name;
        ASSERT_EQ(x.index(), y.index()) << name;
        if (auto* d = std::get_if<DiffuseBsdf>(&x)) {
            auto* e = std::get_if<DiffuseBsdf>(&y);
            EXPECT_EQ(d->reflectance, e->reflectance) << name;
            EXPECT_EQ(d->two_sided, e->two_sided) << name;
            EXPECT_EQ(d->alpha, e->alpha) << name;
            EXPECT_EQ(d->fast_approx, e->fast_approx) << name;
        } else if (auto* c = std::get_if<ConductorBsdf>(&x)) {
            auto* e = std::get_if<ConductorBsdf>(&y);
            EXPECT_EQ(c->eta, e->eta) << name;
            EXPECT_EQ(c->k, e->k) << name;
            EXPECT_EQ(c->has_ior, e->has_ior) << name;
            EXPECT_EQ(c->specular_reflectance, e->specular_reflectance) << name;
            EXPECT_EQ(c->alpha_u, e->alpha_u) << name;
            EXPECT_EQ(c->alpha_v, e->alpha_v) << name;
            EXPECT_EQ(c->distribution, e->distribution) << name;
            EXPECT_EQ(c->two_sided, e->two_sided) << name;
        } else if (auto* g = std::get_if<DielectricBsdf>(&x)) {
            auto* e = std::get_if<DielectricBsdf>(&y);
            EXPECT_EQ(g->eta, e->eta) << name;
            EXPECT_EQ(g->specular_reflectance, e->specular_reflectance) << name;
            EXPECT_EQ(g->specular_transmittance, e->specular_transmittance) << name;
            EXPECT_EQ(g->alpha_u, e->alpha_u) << name;
            EXPECT_EQ(g->alpha_v, e->alpha_v) << name;
            EXPECT_EQ(g->distribution, e->distribution) << name;
        }
    }
    ASSERT_EQ(a.shapes.size(), b.shapes.size());
    for (size_t i = 0; i < a.shapes.size(); ++i) {
        const ShapeDesc &p = a.shapes[i], &q = b.shapes[i];
        EXPECT_EQ(p.type, q.type) << i;
        EXPECT_EQ(p.name, q.name) << i;
        EXPECT_EQ(p.to_world.m, q.to_world.m) << i;
        EXPECT_EQ(p.file, q.file) << i;
        EXPECT_EQ(p.center, q.center) << i;
        EXPECT_EQ(p.radius, q.radius) << i;
        EXPECT_EQ(p.material, q.material) << i;
        EXPECT_EQ(p.flip_normals, q.flip_normals) << i;
        EXPECT_EQ(p.face_normals, q.face_normals) << i;
        EXPECT_EQ(p.flip_tex_coords, q.flip_tex_coords) << i;
        ASSERT_EQ(p.emitter.has_value(), q.emitter.has_value()) << i;
        if (p.emitter) {
            EXPECT_EQ(p.emitter->radiance, q.emitter->radiance) << i;
            EXPECT_EQ(p.emitter->two_sided, q.emitter->two_sided) << i;
        }
    }
    ASSERT_EQ(a.lights.size(), b.lights.size());
    for (size_t i = 0; i < a.lights.size(); ++i) {
        const LightDesc &p = a.lights[i], &q = b.lights[i];
        EXPECT_EQ(p.type, q.type);
        EXPECT_EQ(p.position, q.position);
        EXPECT_EQ(p.intensity, q.intensity);
        EXPECT_EQ(p.to_world.m, q.to_world.m);
        EXPECT_EQ(p.cutoff_angle, q.cutoff_angle);
        EXPECT_EQ(p.beam_width, q.beam_width);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(p.direction[k], q.direction[k], 1e-15);  // renormalised
        EXPECT_EQ(p.irradiance, q.irradiance);
        EXPECT_EQ(p.radiance, q.radiance);
        EXPECT_EQ(p.file, q.file);
        EXPECT_EQ(p.scale, q.scale);
    }
}

void expect_round_trip(const SceneDesc& d, const std::string& dir = "") {
    std::string yaml = write_scene_yaml(d, dir);
    SceneDesc back = parse_scene_string(yaml, (dir.empty() ? std::string("") : dir + "/") + "roundtrip.yaml");
    SCOPED_TRACE(yaml);
    expect_same(d, back);
    std::string again = write_scene_yaml(back, dir);
    EXPECT_EQ(again.substr(again.find("omega: 1")), yaml.substr(yaml.find("omega: 1")));
}

const char* kLitBox = R"(<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>)";

}  // namespace

// ---------------------------------------------------------------------------------------------
// The two shared scenes

// The shared Cornell box as a Mitsuba 0.6 export writes it (tests/data/mitsuba06: camelCase,
// lookat, ldrfilm, strictNormals, 3-value spectra) imports to the same scene as the 3.0 file,
// without a warning: every construct in it is supported.
TEST(MitsubaImporter, CornellBoxIn06SyntaxEqualsThe30File) {
    if (!have_shared()) GTEST_SKIP() << "no " << shared_scene("cornell-box");
    MitsubaOptions opt;
    opt.defines = {{"integrator", "path"}, {"max_depth", "65"}};
    SceneDesc v3 = import_mitsuba_file(shared_scene("cornell-box"), opt);
    SceneDesc v06 = import_mitsuba_file((omega::test::source_root() / "tests/data/mitsuba06/cornell-box.xml").string());
    EXPECT_TRUE(v06.warnings.empty()) << all_warnings(v06);
    EXPECT_EQ(v06.integrator.max_depth, 65);
    EXPECT_EQ(v06.sensor.halt.spp, v3.sensor.halt.spp);
    EXPECT_EQ(v06.sensor.film.width, v3.sensor.film.width);
    EXPECT_EQ(v06.sensor.film.filter, v3.sensor.film.filter);
    EXPECT_FLOAT_EQ(v06.sensor.fov, v3.sensor.fov);
    EXPECT_FLOAT_EQ(v06.sensor.near_clip, 0.1f);
    EXPECT_FLOAT_EQ(v06.sensor.far_clip, 100.f);
    for (int i = 0; i < 16; ++i) EXPECT_NEAR(v06.sensor.to_world.m[size_t(i)], v3.sensor.to_world.m[size_t(i)], 1e-12) << i;
    ASSERT_EQ(v06.shapes.size(), v3.shapes.size());
    for (size_t i = 0; i < v3.shapes.size(); ++i) {
        EXPECT_EQ(v06.shapes[i].to_world.m, v3.shapes[i].to_world.m) << i;
        EXPECT_EQ(v06.shapes[i].material, v3.shapes[i].material) << i;
    }
    ASSERT_EQ(v06.materials.size(), v3.materials.size());
    for (const auto& [name, m] : v3.materials) {
        const auto& a = std::get<DiffuseBsdf>(m.bsdf);
        const auto& b = std::get<DiffuseBsdf>(v06.materials.at(name).bsdf);
        EXPECT_EQ(a.reflectance, b.reflectance) << name;
    }
    ASSERT_TRUE(v06.shapes[7].emitter);
    EXPECT_EQ(v06.shapes[7].emitter->radiance, v3.shapes[7].emitter->radiance);
    // The far clipping plane cuts nothing in the box, so the build has nothing to say.
    v06.sensor.film.width = v06.sensor.film.height = 8;
    v06.sensor.film.crop = {0, 0, 8, 8};
    EXPECT_TRUE(Scene::build(v06)->warnings().empty());
    v06.sensor.far_clip = 5;
    auto clipped = Scene::build(v06);
    ASSERT_EQ(clipped->warnings().size(), 1u);
    EXPECT_NE(clipped->warnings()[0].find("beyond far_clip 5"), std::string::npos) << clipped->warnings()[0];
}

TEST(MitsubaImporter, CornellBox) {
    if (!have_shared()) GTEST_SKIP() << "no " << shared_scene("cornell-box");
    SceneDesc d = import_mitsuba_file(shared_scene("cornell-box"));
    EXPECT_EQ(d.integrator.type, IntegratorType::Path);
    EXPECT_EQ(d.integrator.max_depth, 30);  // the file's <default>
    EXPECT_TRUE(has_warning(d, "scene.xml:11: integrator: integrator 'path_guiding_integrator' is not supported"))
        << all_warnings(d);
    EXPECT_EQ(d.warnings.size(), 1u) << all_warnings(d);
    EXPECT_EQ(d.sensor.type, SensorType::Perspective);
    EXPECT_FLOAT_EQ(d.sensor.fov, 19.5f);
    EXPECT_EQ(d.sensor.fov_axis, 'x');
    expect_mat(d.sensor.to_world, {-1, 0, 0, 0, 0, 1, 0, 1, 0, 0, -1, 6.8, 0, 0, 0, 1});
    EXPECT_EQ(d.sensor.film.width, 1024);
    EXPECT_EQ(d.sensor.film.height, 1024);
    EXPECT_EQ(d.sensor.film.filter, FilterType::Tent);
    EXPECT_EQ(d.sensor.halt.spp, 64);
    ASSERT_EQ(d.shapes.size(), 8u);
    const ShapeDesc& light = d.shapes[7];
    EXPECT_EQ(light.name, "Light");
    EXPECT_EQ(light.type, ShapeType::Rectangle);
    expect_mat(light.to_world, {0.235, -1.66103e-008, -7.80685e-009, -0.005, -2.05444e-008, 3.90343e-009, -0.0893, 1.98,
                                2.05444e-008, 0.19, 8.30516e-009, -0.03, 0, 0, 0, 1});
    ASSERT_TRUE(light.emitter);
    expect_rgb(light.emitter->radiance, 17, 12, 4);
    EXPECT_FALSE(light.emitter->two_sided);
    EXPECT_EQ(light.material, "LightBSDF");
    auto& lb = std::get<DiffuseBsdf>(d.materials.at("LightBSDF").bsdf);
    expect_rgb(lb.reflectance, 0, 0, 0);
    EXPECT_TRUE(lb.two_sided);  // wrapped in twosided
    auto& left = std::get<DiffuseBsdf>(d.materials.at("LeftWallBSDF").bsdf);
    expect_rgb(left.reflectance, 0.63f, 0.065f, 0.05f);
    EXPECT_EQ(d.shapes[5].name, "ShortBox");
    EXPECT_EQ(d.shapes[5].type, ShapeType::Cube);
    EXPECT_EQ(d.shapes[5].to_world(0, 3), 0.328631);
    EXPECT_EQ(d.shapes[5].to_world(1, 2), -0.3);
    // The same scene as the hand translation in scenes/, apart from max_depth (a placeholder).
    SceneDesc y = parse_scene_file((omega::test::source_root() / "scenes/cornell-box.yaml").string());
    for (size_t i = 0; i < 8; ++i) EXPECT_EQ(d.shapes[i].to_world.m, y.shapes[i].to_world.m) << i;
}

TEST(MitsubaImporter, CornellBoxDefinesOverride) {
    if (!have_shared()) GTEST_SKIP() << "no " << shared_scene("cornell-box");
    MitsubaOptions opt;
    opt.defines = {{"resx", "256"}, {"resy", "128"}, {"max_depth", "65"}, {"integrator", "path"}};
    SceneDesc d = import_mitsuba_file(shared_scene("cornell-box"), opt);
    EXPECT_EQ(d.sensor.film.width, 256);
    EXPECT_EQ(d.sensor.film.height, 128);
    EXPECT_EQ(d.sensor.film.crop, (std::array<int, 4>{0, 0, 256, 128}));
    EXPECT_EQ(d.integrator.max_depth, 65);
    EXPECT_TRUE(d.warnings.empty()) << all_warnings(d);
}

TEST(MitsubaImporter, VeachMis) {
    if (!have_shared()) GTEST_SKIP() << "no " << shared_scene("cornell-box");
    SceneDesc d = import_mitsuba_file(shared_scene("veach-mis"));
    EXPECT_EQ(d.sensor.film.width, 1280);
    EXPECT_EQ(d.sensor.film.height, 720);
    EXPECT_FLOAT_EQ(d.sensor.fov, 35.f);
    EXPECT_EQ(d.sensor.to_world(0, 3), 28.2792);
    ASSERT_EQ(d.shapes.size(), 9u);
    const std::pair<const char*, float> plates[] = {
        {"SmoothBSDF", 0.01f}, {"GlossyBSDF", 0.05f}, {"RoughBSDF", 0.1f}, {"SuperRoughBSDF", 0.25f}};
    for (auto [name, alpha] : plates) {
        SCOPED_TRACE(name);
        auto& c = std::get<ConductorBsdf>(d.materials.at(name).bsdf);
        EXPECT_EQ(c.distribution, MicrofacetType::Beckmann);
        EXPECT_FLOAT_EQ(c.alpha_u, alpha);
        EXPECT_FLOAT_EQ(c.alpha_v, alpha);
        EXPECT_TRUE(c.has_ior);
        expect_rgb(c.eta, 0.200438f, 0.924033f, 1.10221f);
        expect_rgb(c.k, 3.91295f, 2.45285f, 2.14219f);
        expect_rgb(c.specular_reflectance, 0.3f, 0.3f, 0.3f);
        EXPECT_TRUE(c.two_sided);
    }
    const ShapeDesc& small = d.shapes[7];
    EXPECT_EQ(small.name, "Null_0003");
    EXPECT_EQ(small.type, ShapeType::Sphere);
    EXPECT_EQ(small.center, (Vec3d{0, 6.5, 2.7}));
    EXPECT_EQ(small.radius, 0.05);
    ASSERT_TRUE(small.emitter);
    expect_rgb(small.emitter->radiance, 3039.64f, 3039.64f, 3039.64f);
    EXPECT_EQ(d.shapes[8].name, "SuperRough");
    EXPECT_EQ(d.shapes[8].to_world(0, 3), 10.6769);
}

TEST(MitsubaImporter, SharedScenesRoundTripThroughYaml) {
    if (!have_shared()) GTEST_SKIP() << "no " << shared_scene("cornell-box");
    for (const char* name : {"cornell-box", "veach-mis"}) {
        SCOPED_TRACE(name);
        expect_round_trip(import_mitsuba_file(shared_scene(name)));
    }
}

// ---------------------------------------------------------------------------------------------
// Variables

TEST(MitsubaImporter, DefaultsAndSubstitution) {
    const std::string body = R"(
<default name="w" value="64"/>
<default name="wh" value="32"/>
<default name="r" value="0.25"/>
<sensor type="perspective"><float name="fov" value="1$r"/>
  <film type="hdrfilm"><integer name="width" value="$w"/><integer name="height" value="$wh"/></film></sensor>
<bsdf type="diffuse" id="a"><rgb name="reflectance" value="$r, 0.5, $r"/></bsdf>
<shape type="sphere"><ref id="a"/></shape>)" + std::string(kLitBox);
    SceneDesc d = import(body);
    EXPECT_EQ(d.sensor.film.width, 64);
    EXPECT_EQ(d.sensor.film.height, 32);  // $wh is not $w followed by "h"
    EXPECT_FLOAT_EQ(d.sensor.fov, 10.25f);
    expect_rgb(std::get<DiffuseBsdf>(d.materials.at("a").bsdf).reflectance, 0.25f, 0.5f, 0.25f);
    MitsubaOptions opt;
    opt.defines = {{"w", "100"}};
    EXPECT_EQ(import(body, opt).sensor.film.width, 100);
    opt.defines = {{"nope", "1"}};
    EXPECT_TRUE(has_warning(import(body, opt), "define nope=1 is not used"));
}

TEST(MitsubaImporter, UndefinedVariableIsAnErrorWithItsLine) {
    EXPECT_EQ(import_error("\n<shape type=\"sphere\">\n<float name=\"radius\" value=\"$rad\"/></shape>"),
              "scene.xml:4: shape[0].radius: undefined variable $rad (add <default name=\"rad\" value=\"...\"/>)");
}

// ---------------------------------------------------------------------------------------------
// Transforms

Mat4 shape_matrix(const std::string& ops) {
    SceneDesc d = import("<shape type=\"cube\"><transform name=\"to_world\">" + ops + "</transform></shape>" + kLitBox);
    return d.shapes.at(0).to_world;
}

TEST(MitsubaImporter, TransformKinds) {
    expect_mat(shape_matrix(R"(<translate x="1" y="2" z="3"/>)"), {1, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1});
    expect_mat(shape_matrix(R"(<translate value="1 2 3"/>)"), {1, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1});
    expect_mat(shape_matrix(R"(<scale value="2"/>)"), {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1});
    expect_mat(shape_matrix(R"(<scale x="2" z="3"/>)"), {2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 3, 0, 0, 0, 0, 1});
    expect_mat(shape_matrix(R"(<rotate y="1" angle="90"/>)"), {0, 0, 1, 0, 0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 0, 1}, 1e-15);
    expect_mat(shape_matrix(R"(<rotate value="0, 0, 1" angle="90"/>)"), {0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
               1e-15);
    expect_mat(shape_matrix(R"(<matrix value="1 0 0 5  0 2 0 6  0 0 3 7  0 0 0 1"/>)"),
               {1, 0, 0, 5, 0, 2, 0, 6, 0, 0, 3, 7, 0, 0, 0, 1});
    // Mitsuba's lookat: +z towards the target, +x = up x dir.
    expect_mat(shape_matrix(R"(<lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/>)"),
               {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 5, 0, 0, 0, 1}, 1e-15);
    // Applied in order, the first to the points first: translate after scale = T * S.
    expect_mat(shape_matrix(R"(<scale value="2"/><translate x="1"/>)"), {2, 0, 0, 1, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1});
    expect_mat(shape_matrix(R"(<translate x="1"/><scale value="2"/>)"), {2, 0, 0, 2, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1});
}

TEST(MitsubaImporter, BadTransformsAreErrors) {
    EXPECT_EQ(import_error("<shape type=\"cube\">\n<transform name=\"to_world\"><scale value=\"0\"/></transform></shape>"),
              "scene.xml:3: shape[0].to_world: matrix is singular");
    EXPECT_EQ(import_error("<shape type=\"cube\">\n<transform name=\"to_world\">\n<matrix value=\"1 2 3\"/></transform></shape>"),
              "scene.xml:4: shape[0].to_world: <matrix> needs 16 numbers, got 3");
}

// ---------------------------------------------------------------------------------------------
// Plugins

TEST(MitsubaImporter, MaterialsMapToOmegaBsdfs) {
    SceneDesc d = import(R"(
<bsdf type="conductor" id="mirror"/>
<bsdf type="conductor" id="gold"><string name="material" value="Au"/></bsdf>
<bsdf type="roughconductor" id="rough"/>
<bsdf type="roughconductor" id="ggx"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.2"/>
  <string name="distribution" value="ggx"/></bsdf>
<bsdf type="dielectric" id="glass"><string name="int_ior" value="water"/><float name="ext_ior" value="1"/></bsdf>
<bsdf type="roughdielectric" id="frosted"><float name="int_ior" value="1.5"/><float name="alpha" value="0.3"/></bsdf>
<bsdf type="diffuse" id="onesided"/>
<shape type="cube"><ref id="mirror"/></shape>
<shape type="cube"><ref id="gold"/></shape>
<shape type="cube"><ref id="rough"/></shape>
<shape type="cube"><ref id="ggx"/></shape>
<shape type="cube"><ref id="glass"/></shape>
<shape type="cube"><ref id="frosted"/></shape>
<shape type="cube"><ref name="bsdf" id="onesided"/></shape>
<shape type="cube"/>
)" + std::string(kLitBox));
    auto& mirror = std::get<ConductorBsdf>(d.materials.at("mirror").bsdf);
    EXPECT_FALSE(mirror.has_ior);  // Mitsuba 3's default material "none": a perfect mirror
    EXPECT_EQ(mirror.alpha_u, 0.f);
    EXPECT_FALSE(mirror.two_sided);  // one-sided unless wrapped in twosided
    EXPECT_TRUE(std::get<ConductorBsdf>(d.materials.at("gold").bsdf).has_ior);
    auto& rough = std::get<ConductorBsdf>(d.materials.at("rough").bsdf);
    EXPECT_FLOAT_EQ(rough.alpha_u, 0.1f);  // Mitsuba's defaults
    EXPECT_EQ(rough.distribution, MicrofacetType::Beckmann);
    auto& ggx = std::get<ConductorBsdf>(d.materials.at("ggx").bsdf);
    EXPECT_FLOAT_EQ(ggx.alpha_u, 0.1f);
    EXPECT_FLOAT_EQ(ggx.alpha_v, 0.2f);
    EXPECT_EQ(ggx.distribution, MicrofacetType::GGX);
    EXPECT_FLOAT_EQ(std::get<DielectricBsdf>(d.materials.at("glass").bsdf).eta, 1.333f);
    auto& frosted = std::get<DielectricBsdf>(d.materials.at("frosted").bsdf);
    EXPECT_FLOAT_EQ(frosted.eta, 1.5f / 1.000277f);
    EXPECT_FLOAT_EQ(frosted.alpha_u, 0.3f);
    EXPECT_FALSE(std::get<DiffuseBsdf>(d.materials.at("onesided").bsdf).two_sided);
    auto& def = std::get<DiffuseBsdf>(d.materials.at(d.shapes[7].material).bsdf);
    expect_rgb(def.reflectance, 0.5f, 0.5f, 0.5f);
    EXPECT_FALSE(def.two_sided);
    ASSERT_EQ(d.warnings.size(), 1u) << all_warnings(d);
    EXPECT_EQ(d.warnings[0], "scene.xml:1: scene: no <sensor>: using Omega's default camera");
    expect_round_trip(d);
}

// checkerboard on a diffuse reflectance and a conductor's specular_reflectance, and mask with a
// constant, a default and a bitmap opacity, wrapped either way round with twosided.
TEST(MitsubaImporter, CheckerboardAndMaskMapToTexturesAndOpacity) {
    TempDir dir;
    dir.write("alpha.ppm", std::string("P6\n2 1\n255\n") + std::string("\xff\xff\xff\x00\x00\x00", 6));
    auto xml = dir.write("scene.xml", R"(<scene version="3.0.0">
<bsdf type="diffuse" id="wall"><texture type="checkerboard" name="reflectance">
  <rgb name="color0" value="0.8, 0.8, 0.8"/><rgb name="color1" value="0.1, 0.1, 0.15"/>
  <transform name="to_uv"><scale x="4" y="4"/></transform></texture></bsdf>
<bsdf type="roughconductor" id="metal"><texture type="checkerboard" name="specular_reflectance">
  <float name="color0" value="1"/><float name="color1" value="0.25"/></texture></bsdf>
<bsdf type="mask" id="half"><float name="opacity" value="0.3"/><bsdf type="twosided"><bsdf type="diffuse"/></bsdf></bsdf>
<bsdf type="twosided" id="def"><bsdf type="mask"><bsdf type="diffuse"/></bsdf></bsdf>
<bsdf type="mask" id="leaf"><texture type="bitmap" name="opacity"><string name="filename" value="alpha.ppm"/>
  <boolean name="raw" value="true"/></texture><bsdf type="diffuse"/></bsdf>
<shape type="rectangle"><ref id="wall"/></shape>
<shape type="sphere"><ref id="metal"/></shape>
<shape type="rectangle"><ref id="half"/></shape>
<shape type="rectangle"><ref id="def"/></shape>
<shape type="rectangle"><ref id="leaf"/></shape>
<bsdf type="bumpmap" id="bumped"><texture type="bitmap" name="arbitrary"><string name="filename" value="alpha.ppm"/>
  <boolean name="raw" value="true"/></texture><float name="scale" value="0.08"/>
  <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></bsdf>
<bsdf type="mask" id="both"><float name="opacity" value="0.9"/><bsdf type="bumpmap"><texture type="checkerboard"/>
  <bsdf type="roughconductor"/></bsdf></bsdf>
<shape type="rectangle"><ref id="bumped"/></shape>
<shape type="rectangle"><ref id="both"/></shape>
)" + std::string(kLitBox) + "</scene>");
    SceneDesc d = import_mitsuba_file(xml.string());
    ASSERT_EQ(d.warnings.size(), 1u) << all_warnings(d);  // only the missing sensor
    const auto& wall = *d.materials.at("wall").reflectance_texture;
    EXPECT_TRUE(wall.checker);
    EXPECT_EQ(wall.color1, (Rgb{0.1f, 0.1f, 0.15f}));
    EXPECT_EQ(wall.to_uv.m, (std::array<float, 6>{4, 0, 0, 0, 4, 0}));
    const auto& metal = *d.materials.at("metal").specular_texture;
    EXPECT_TRUE(metal.checker);
    EXPECT_EQ(metal.color0, Rgb(1.f));
    EXPECT_EQ(metal.color1, Rgb(0.25f));
    EXPECT_FLOAT_EQ(d.materials.at("half").opacity, 0.3f);
    EXPECT_TRUE(std::get<DiffuseBsdf>(d.materials.at("half").bsdf).two_sided);
    EXPECT_FLOAT_EQ(d.materials.at("def").opacity, 0.5f);  // Mitsuba's default
    EXPECT_TRUE(std::get<DiffuseBsdf>(d.materials.at("def").bsdf).two_sided);
    ASSERT_TRUE(d.materials.at("leaf").opacity_texture);
    EXPECT_TRUE(d.materials.at("leaf").opacity_texture->raw);
    EXPECT_FALSE(std::get<DiffuseBsdf>(d.materials.at("leaf").bsdf).two_sided);
    const MaterialDesc& bumped = d.materials.at("bumped");
    ASSERT_TRUE(bumped.bump_texture);
    EXPECT_EQ(bumped.bump_texture->file, (dir.path / "alpha.ppm").lexically_normal().string());
    EXPECT_TRUE(bumped.bump_texture->raw);
    EXPECT_FLOAT_EQ(bumped.bump_scale, 0.08f);
    EXPECT_TRUE(std::get<DiffuseBsdf>(bumped.bsdf).two_sided);
    const MaterialDesc& both = d.materials.at("both");
    EXPECT_FLOAT_EQ(both.opacity, 0.9f);
    ASSERT_TRUE(both.bump_texture);
    EXPECT_TRUE(both.bump_texture->checker);
    EXPECT_EQ(both.bump_scale, 1.f);  // Mitsuba's default
    EXPECT_TRUE(std::holds_alternative<ConductorBsdf>(both.bsdf));
    expect_round_trip(d, dir.path.string());
    auto scene = Scene::build(d);
    EXPECT_TRUE(scene->shapes()[4].masked());
    EXPECT_FALSE(scene->shapes()[0].masked());
}

// Both syntaxes (0.6's camelCase too), Mitsuba's defaults (BK7 in air) when nothing is given.
TEST(MitsubaImporter, ThinDielectricMapsToTheThinSheet) {
    SceneDesc d = import(R"(
<bsdf type="thindielectric" id="def"/>
<bsdf type="thindielectric" id="pane"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/>
  <rgb name="specular_transmittance" value="0.9, 0.8, 0.7"/><rgb name="specular_reflectance" value="0.5"/></bsdf>
<shape type="rectangle"><ref id="def"/></shape>
<shape type="rectangle"><ref id="pane"/></shape>
)" + std::string(kLitBox));
    const auto& def = std::get<ThinDielectricBsdf>(d.materials.at("def").bsdf);
    EXPECT_FLOAT_EQ(def.eta, 1.5046f / 1.000277f);
    expect_rgb(def.specular_reflectance, 1.f, 1.f, 1.f);
    expect_rgb(def.specular_transmittance, 1.f, 1.f, 1.f);
    const auto& pane = std::get<ThinDielectricBsdf>(d.materials.at("pane").bsdf);
    EXPECT_FLOAT_EQ(pane.eta, 1.5f);
    expect_rgb(pane.specular_reflectance, 0.5f, 0.5f, 0.5f);
    expect_rgb(pane.specular_transmittance, 0.9f, 0.8f, 0.7f);
    ASSERT_EQ(d.warnings.size(), 1u) << all_warnings(d);  // only the missing sensor
    expect_round_trip(d);

    SceneDesc legacy = import_mitsuba_string(R"(<scene version="0.6.0">
<bsdf type="thindielectric" id="pane"><float name="intIOR" value="1.33"/><float name="extIOR" value="1"/></bsdf>
<shape type="rectangle"><ref id="pane"/></shape></scene>)", "scene.xml");
    EXPECT_FLOAT_EQ(std::get<ThinDielectricBsdf>(legacy.materials.at("pane").bsdf).eta, 1.33f);
}

// Both syntaxes, Mitsuba's defaults written out (Omega's own differ: ggx), parameters by name.
TEST(MitsubaImporter, PlasticMapsToTheCoatedBsdf) {
    SceneDesc d = import(R"(
<bsdf type="plastic" id="def"/>
<bsdf type="twosided" id="red"><bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.8, 0.1, 0.1"/>
  <float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/><boolean name="nonlinear" value="true"/>
  <rgb name="specular_reflectance" value="0.5"/></bsdf></bsdf>
<bsdf type="roughplastic" id="rdef"/>
<bsdf type="roughplastic" id="ggx"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/>
  <string name="int_ior" value="bk7"/><string name="ext_ior" value="water"/></bsdf>
<shape type="cube"><ref id="def"/></shape>
<shape type="cube"><ref id="red"/></shape>
<shape type="cube"><ref id="rdef"/></shape>
<shape type="cube"><ref id="ggx"/></shape>
)" + std::string(kLitBox));
    const auto& def = std::get<PlasticBsdf>(d.materials.at("def").bsdf);
    EXPECT_FLOAT_EQ(def.eta, 1.49f / 1.000277f);  // polypropylene in air
    EXPECT_NEAR(def.fdr_int, plastic_fdr_int(1.49f / 1.000277f), 1e-7f);
    expect_rgb(def.diffuse_reflectance, 0.5f, 0.5f, 0.5f);
    expect_rgb(def.specular_reflectance, 1.f, 1.f, 1.f);
    EXPECT_FALSE(def.nonlinear);
    EXPECT_EQ(def.alpha, 0.f);
    EXPECT_FALSE(def.two_sided);
    const auto& red = std::get<PlasticBsdf>(d.materials.at("red").bsdf);
    EXPECT_FLOAT_EQ(red.eta, 1.5f);
    expect_rgb(red.diffuse_reflectance, 0.8f, 0.1f, 0.1f);
    expect_rgb(red.specular_reflectance, 0.5f, 0.5f, 0.5f);
    EXPECT_TRUE(red.nonlinear);
    EXPECT_TRUE(red.two_sided);
    const auto& rdef = std::get<PlasticBsdf>(d.materials.at("rdef").bsdf);
    EXPECT_FLOAT_EQ(rdef.alpha, 0.1f);
    EXPECT_EQ(rdef.distribution, MicrofacetType::Beckmann);
    const auto& ggx = std::get<PlasticBsdf>(d.materials.at("ggx").bsdf);
    EXPECT_FLOAT_EQ(ggx.alpha, 0.2f);
    EXPECT_EQ(ggx.distribution, MicrofacetType::GGX);
    EXPECT_FLOAT_EQ(ggx.eta, 1.5046f / 1.333f);
    ASSERT_EQ(d.warnings.size(), 1u) << all_warnings(d);  // only the missing sensor
    expect_round_trip(d);

    // Mitsuba 0.6: camelCase names.
    SceneDesc old = import_mitsuba_string(R"(<scene version="0.6.0">
<bsdf type="roughplastic" id="p"><rgb name="diffuseReflectance" value="0.2, 0.3, 0.4"/>
  <float name="intIOR" value="1.6"/><float name="extIOR" value="1.1"/><rgb name="specularReflectance" value="0.7"/>
  <boolean name="nonlinear" value="true"/><float name="alpha" value="0.3"/></bsdf>
<shape type="cube"><ref id="p"/></shape>
)" + std::string(kLitBox) + "</scene>\n", "scene.xml");
    const auto& p = std::get<PlasticBsdf>(old.materials.at("p").bsdf);
    expect_rgb(p.diffuse_reflectance, 0.2f, 0.3f, 0.4f);
    expect_rgb(p.specular_reflectance, 0.7f, 0.7f, 0.7f);
    EXPECT_FLOAT_EQ(p.eta, 1.6f / 1.1f);
    EXPECT_TRUE(p.nonlinear);
    EXPECT_FLOAT_EQ(p.alpha, 0.3f);
    EXPECT_EQ(p.distribution, MicrofacetType::Beckmann);
    EXPECT_EQ(old.warnings.size(), 1u) << all_warnings(old);  // the missing sensor (0.6 syntax itself is no warning)
}

TEST(MitsubaImporter, ValueErrorsNameTheParameterLine) {
    EXPECT_EQ(import_error("<bsdf type=\"roughconductor\" id=\"x\">\n\n<float name=\"alpha\" value=\"2\"/></bsdf>\n"
                           "<shape type=\"cube\"><ref id=\"x\"/></shape>"),
              "scene.xml:4: bsdf(x).alpha: must be in [0, 1], got 2");
    EXPECT_EQ(import_error("<shape type=\"cube\"><ref id=\"missing\"/></shape>"),
              "scene.xml:2: shape[0]: reference to an unknown id 'missing'");
    EXPECT_EQ(import_error("<shape type=\"obj\">\n<string name=\"filename\" value=\"nope.obj\"/></shape>"),
              "scene.xml:3: shape[0].filename: cannot open 'nope.obj': No such file or directory");
}

// Found by fuzz_mitsuba_xml: a film size past int's range was converted with int(), which is
// undefined (UBSan: "1.44444e+10 is outside the range of representable values of type 'int'").
TEST(MitsubaImporter, FilmSizesPastIntRangeAreErrorsWithTheirLine) {
    for (const char* name : {"width", "height", "crop_offset_x", "crop_width"}) {
        const std::string e = import_error(std::string("<sensor type=\"perspective\"><film type=\"hdrfilm\">\n<integer name=\"") +
                                           name + "\" value=\"14444444446\"/></film></sensor>");
        EXPECT_NE(e.find("scene.xml:3: "), std::string::npos) << e;
        EXPECT_NE(e.find(std::string("'") + name + "' must be an integer within +-2^31, got 14444444446"), std::string::npos) << e;
    }
}

TEST(MitsubaImporter, EmittersAndSensors) {
    SceneDesc d = import(R"(
<sensor type="thinlens"><float name="fov" value="40"/><string name="fov_axis" value="y"/>
  <float name="aperture_radius" value="0.1"/><float name="focus_distance" value="3"/>
  <film type="hdrfilm"><integer name="width" value="200"/><integer name="height" value="100"/>
    <rfilter type="gaussian"><float name="stddev" value="0.3"/></rfilter></film></sensor>
<emitter type="point"><point name="position" x="1" y="2" z="3"/><rgb name="intensity" value="5"/></emitter>
<emitter type="spot"><transform name="to_world"><lookat origin="0,5,0" target="0,0,0" up="0,0,1"/></transform>
  <rgb name="intensity" value="10"/><float name="cutoff_angle" value="30"/></emitter>
<emitter type="directional"><vector name="direction" x="0" y="-2" z="0"/><spectrum name="irradiance" value="3"/></emitter>
<emitter type="constant"><rgb name="radiance" value="0.1, 0.2, 0.3"/></emitter>
)");
    EXPECT_EQ(d.sensor.type, SensorType::ThinLens);
    EXPECT_EQ(d.sensor.fov_axis, 'y');
    EXPECT_FLOAT_EQ(d.sensor.aperture_radius, 0.1f);
    EXPECT_FLOAT_EQ(d.sensor.focus_distance, 3.f);
    EXPECT_EQ(d.sensor.film.filter, FilterType::Gaussian);
    EXPECT_FLOAT_EQ(d.sensor.film.gaussian_stddev, 0.3f);
    ASSERT_EQ(d.lights.size(), 4u);
    EXPECT_EQ(d.lights[0].position, (Vec3d{1, 2, 3}));
    expect_rgb(d.lights[0].intensity, 5, 5, 5);
    EXPECT_EQ(d.lights[1].type, LightType::Spot);
    EXPECT_FLOAT_EQ(d.lights[1].cutoff_angle, 30.f);
    EXPECT_FLOAT_EQ(d.lights[1].beam_width, 22.5f);
    EXPECT_NEAR(d.lights[1].to_world(1, 2), -1, 1e-15);  // looks down
    EXPECT_EQ(d.lights[2].direction, (Vec3d{0, -1, 0}));
    expect_rgb(d.lights[3].radiance, 0.1f, 0.2f, 0.3f);
    EXPECT_TRUE(d.warnings.empty()) << all_warnings(d);
    expect_round_trip(d);

    // fov_axis diagonal: converted to the horizontal field of view.
    SceneDesc o = import(R"(<sensor type="perspective"><float name="fov" value="90"/><string name="fov_axis" value="diagonal"/>
  <film type="hdrfilm"><integer name="width" value="300"/><integer name="height" value="400"/></film></sensor>)" +
                         std::string(kLitBox));
    EXPECT_NEAR(o.sensor.fov, 2 * std::atan(0.6) * 180 / 3.14159265358979, 1e-4);
    EXPECT_EQ(o.sensor.film.filter, FilterType::Gaussian);  // Mitsuba's default filter
    SceneDesc ortho = import(R"(<sensor type="orthographic"><transform name="to_world"><scale value="3"/></transform></sensor>)" +
                             std::string(kLitBox));
    EXPECT_EQ(ortho.sensor.type, SensorType::Orthographic);
    EXPECT_EQ(ortho.sensor.to_world(0, 0), 3);
}

TEST(MitsubaImporter, MeshesResolveAgainstTheSceneFolder) {
    TempDir dir;
    dir.write("meshes/tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    auto xml = dir.write("scene.xml", R"(<scene version="3.0.0">
<shape type="obj"><string name="filename" value="meshes/tri.obj"/><boolean name="face_normals" value="true"/></shape>
<shape type="ply"><string name="filename" value="meshes/tri.obj"/><boolean name="flip_normals" value="true"/></shape>
)" + std::string(kLitBox) + "</scene>");
    SceneDesc d = import_mitsuba_file(xml.string());
    ASSERT_EQ(d.shapes.size(), 3u);
    EXPECT_EQ(d.shapes[0].type, ShapeType::Mesh);
    EXPECT_EQ(d.shapes[0].file, (dir.path / "meshes/tri.obj").lexically_normal().string());
    EXPECT_TRUE(d.shapes[0].face_normals);
    EXPECT_TRUE(d.shapes[1].flip_normals);
    // Written relative to the YAML's folder, and read back to the same absolute path.
    std::string yaml = write_scene_yaml(d, dir.path.string());
    EXPECT_NE(yaml.find("file: \"meshes/tri.obj\""), std::string::npos) << yaml;
    expect_round_trip(d, dir.path.string());
}

// Mitsuba 0.6's roughdiffuse (camelCase names) is Oren-Nayar in DiffuseBsdf; an envmap is an
// image light (no longer a constant), its file resolved against the XML's folder, read by
// Scene::build, and written back to YAML relative to the YAML's folder.
TEST(MitsubaImporter, RoughDiffuseAndEnvmap) {
    TempDir dir;
    test::write_image_f32((dir.path / "sky.exr").string(), 4, 3, 3, std::vector<float>(36, 0.5f));
    auto xml = dir.write("scene.xml", R"(<scene version="0.6.0">
<sensor type="perspective"><float name="fov" value="40"/></sensor>
<bsdf type="roughdiffuse" id="rd"><rgb name="diffuseReflectance" value="0.3, 0.4, 0.5"/><float name="alpha" value="0.4"/>
  <boolean name="useFastApprox" value="true"/></bsdf>
<bsdf type="roughdiffuse" id="rd2"/>
<shape type="sphere"><ref id="rd"/></shape>
<shape type="sphere"><ref id="rd2"/></shape>
<emitter type="envmap"><string name="filename" value="sky.exr"/><float name="scale" value="2.5"/>
  <transform name="toWorld"><rotate y="1" angle="30"/></transform></emitter>
</scene>)");
    SceneDesc d = import_mitsuba_file(xml.string());
    EXPECT_TRUE(d.warnings.empty()) << all_warnings(d);
    const auto& rd = std::get<DiffuseBsdf>(d.materials.at("rd").bsdf);
    expect_rgb(rd.reflectance, 0.3f, 0.4f, 0.5f);
    EXPECT_EQ(rd.alpha, 0.4f);
    EXPECT_TRUE(rd.fast_approx);
    EXPECT_FALSE(rd.two_sided);
    const auto& rd2 = std::get<DiffuseBsdf>(d.materials.at("rd2").bsdf);
    EXPECT_EQ(rd2.alpha, 0.2f);  // Mitsuba's default
    EXPECT_FALSE(rd2.fast_approx);
    ASSERT_EQ(d.lights.size(), 1u);
    const LightDesc& l = d.lights[0];
    EXPECT_EQ(l.type, LightType::EnvMap);
    EXPECT_EQ(l.file, (dir.path / "sky.exr").lexically_normal().string());
    EXPECT_EQ(l.scale, 2.5f);
    EXPECT_NEAR(l.to_world(0, 2), std::sin(30 * 3.14159265358979 / 180), 1e-12);
    std::string yaml = write_scene_yaml(d, dir.path.string());
    EXPECT_NE(yaml.find("type: envmap, file: \"sky.exr\""), std::string::npos) << yaml;
    EXPECT_NE(yaml.find("type: roughdiffuse"), std::string::npos) << yaml;
    expect_round_trip(d, dir.path.string());
    auto scene = Scene::build(d);
    ASSERT_GE(scene->environment_light(), 0);
    const auto& env = std::get<EnvMapLight>(scene->lights()[size_t(scene->environment_light())]);
    EXPECT_NEAR(env.map->eval(Vec3{0, 1, 0}).x, 1.25f, 1e-6f);  // 0.5 x scale 2.5
}

TEST(MitsubaImporter, BitmapMapsToATexture) {
    TempDir dir;
    // A 2x1 8-bit PPM: red and black. sRGB-decoded average: (0.5, 0, 0).
    std::string ppm = "P6\n2 1\n255\n";
    ppm += std::string("\xff\x00\x00\x00\x00\x00", 6);
    dir.write("tex.ppm", ppm);
    auto xml = dir.write("scene.xml", R"(<scene version="3.0.0">
<texture type="bitmap" id="t"><string name="filename" value="tex.ppm"/><string name="filter_type" value="nearest"/>
  <string name="wrap_mode" value="clamp"/><boolean name="raw" value="true"/>
  <transform name="to_uv"><scale x="2" y="3"/><translate x="0.5" y="0.25"/></transform></texture>
<bsdf type="diffuse" id="inline"><texture type="bitmap" name="reflectance"><string name="filename" value="tex.ppm"/>
  <string name="format" value="fp16"/>
  <float name="bogus" value="1"/></texture></bsdf>
<bsdf type="diffuse" id="byref"><ref name="reflectance" id="t"/></bsdf>
<bsdf type="plastic" id="plastic"><ref name="diffuse_reflectance" id="t"/></bsdf>
<bsdf type="conductor" id="metal"><ref name="specular_reflectance" id="t"/></bsdf>
<bsdf type="plastic" id="coat"><ref name="specular_reflectance" id="t"/></bsdf>
<bsdf type="conductor" id="odd"><ref name="eta" id="t"/><rgb name="k" value="1"/></bsdf>
<bsdf type="roughconductor" id="rough"><ref name="alpha" id="t"/></bsdf>
<bsdf type="roughdielectric" id="glass"><ref name="specular_reflectance" id="t"/><ref name="specular_transmittance" id="t"/>
  <ref name="alpha" id="t"/></bsdf>
<bsdf type="thindielectric" id="pane"><ref name="specular_transmittance" id="t"/></bsdf>
<bsdf type="roughplastic" id="rp"><ref name="alpha" id="t"/></bsdf>
<bsdf type="roughdiffuse" id="on"><ref name="alpha" id="t"/></bsdf>
<bsdf type="roughconductor" id="aniso"><ref name="alpha_u" id="t"/><float name="alpha_v" value="0.2"/></bsdf>
<bsdf type="diffuse" id="spun"><texture type="bitmap" name="reflectance"><string name="filename" value="tex.ppm"/>
  <transform name="to_uv"><rotate x="1" angle="30"/></transform></texture></bsdf>
<shape type="cube"><ref id="inline"/></shape>
<shape type="cube"><ref id="byref"/></shape>
<shape type="cube"><ref id="plastic"/></shape>
<shape type="cube"><ref id="metal"/></shape>
<shape type="cube"><ref id="spun"/></shape>
<shape type="obj"><string name="filename" value="tri.obj"/><boolean name="flip_tex_coords" value="false"/></shape>
<shape type="cube"><ref id="coat"/></shape>
<shape type="cube"><ref id="odd"/></shape>
<shape type="cube"><ref id="rough"/></shape>
<shape type="cube"><ref id="glass"/></shape>
<shape type="cube"><ref id="pane"/></shape>
<shape type="cube"><ref id="rp"/></shape>
<shape type="cube"><ref id="on"/></shape>
<shape type="cube"><ref id="aniso"/></shape>
)" + std::string(kLitBox) + "</scene>");
    dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n");
    SceneDesc d = import_mitsuba_file(xml.string());
    const std::string file = (dir.path / "tex.ppm").lexically_normal().string();
    const auto& in = d.materials.at("inline").reflectance_texture;
    ASSERT_TRUE(in);
    EXPECT_EQ(in->file, file);
    EXPECT_EQ(in->filter, TexFilter::Bilinear);
    EXPECT_EQ(in->wrap, TexWrap::Repeat);
    EXPECT_FALSE(in->raw);
    EXPECT_TRUE(in->to_uv.is_identity());
    for (const char* m : {"byref", "plastic"}) {
        const auto& t = d.materials.at(m).reflectance_texture;
        ASSERT_TRUE(t) << m;
        EXPECT_EQ(t->file, file);
        EXPECT_EQ(t->filter, TexFilter::Nearest);
        EXPECT_EQ(t->wrap, TexWrap::Clamp);
        EXPECT_TRUE(t->raw);
        EXPECT_EQ(t->to_uv.m, (std::array<float, 6>{2, 0, 0.5f, 0, 3, 0.25f}));
    }
    EXPECT_FALSE(d.shapes[5].flip_tex_coords);
    // Bitmaps are no longer averaged for a diffuse reflectance; other parameters still are, by name.
    EXPECT_FALSE(has_warning(d, "bsdf(inline).reflectance: bitmap")) << all_warnings(d);
    EXPECT_FALSE(has_warning(d, "bsdf(byref).reflectance: bitmap")) << all_warnings(d);
    EXPECT_TRUE(has_warning(d, "scene.xml:7: bsdf(inline).reflectance: parameter 'bogus' (<float>) is not supported"))
        << all_warnings(d);
    // A conductor's specular_reflectance is textured too now.
    ASSERT_TRUE(d.materials.at("metal").specular_texture);
    EXPECT_EQ(d.materials.at("metal").specular_texture->file, file);
    EXPECT_FALSE(has_warning(d, "bsdf(metal)")) << all_warnings(d);
    // So are a plastic's specular_reflectance, a dielectric's reflectance and transmittance and
    // every isotropic alpha; a conductor's eta and an anisotropic alpha_u are not.
    ASSERT_TRUE(d.materials.at("coat").specular_texture);
    for (const char* m : {"rough", "glass", "rp", "on"}) {
        ASSERT_TRUE(d.materials.at(m).alpha_texture) << m;
        EXPECT_EQ(d.materials.at(m).alpha_texture->file, file) << m;
    }
    EXPECT_TRUE(d.materials.at("glass").specular_texture && d.materials.at("glass").transmittance_texture);
    EXPECT_TRUE(d.materials.at("pane").transmittance_texture);
    EXPECT_FALSE(d.materials.at("pane").specular_texture);
    for (const char* m : {"coat", "rough", "glass", "pane", "rp", "on"})
        EXPECT_FALSE(has_warning(d, std::string("bsdf(") + m + ")")) << m << ": " << all_warnings(d);
    EXPECT_TRUE(has_warning(d, "bsdf(odd).eta: bitmap 'tex.ppm': this parameter takes no texture in Omega"))
        << all_warnings(d);
    EXPECT_TRUE(has_warning(d, "bsdf(aniso): alpha_u textures are not supported")) << all_warnings(d);
    EXPECT_TRUE(has_warning(d, "using its average colour [0.5, 0, 0]")) << all_warnings(d);
    EXPECT_TRUE(has_warning(d, "bsdf(spun).reflectance: to_uv mixes in the z axis")) << all_warnings(d);
    EXPECT_TRUE(d.materials.at("spun").reflectance_texture->to_uv.is_identity());
    expect_round_trip(d, dir.path.string());
}

TEST(MitsubaImporter, EverythingUnsupportedIsNamedInAWarning) {
    SceneDesc d = import(R"(
<integrator type="volpath"><boolean name="hide_emitters" value="true"/><integer name="samples_per_pass" value="4"/></integrator>
<sensor type="radiancemeter"><float name="fov" value="30"/><float name="far_clip" value="100"/><string name="focal_length" value="35mm"/>
  <sampler type="stratified"><integer name="sample_count" value="16"/></sampler>
  <film type="specfilm"><string name="pixel_format" value="luminance"/><boolean name="banner" value="false"/>
    <rfilter type="mitchell"/></film></sensor>
<medium type="homogeneous" id="fog"/>
<bsdf type="plastic" id="p"><rgb name="diffuse_reflectance" value="0.2"/></bsdf>
<bsdf type="roughplastic" id="rp"/>
<bsdf type="thindielectric" id="thin"/>
<bsdf type="null" id="n"/>
<bsdf type="hair" id="h"/>
<bsdf type="blendbsdf" id="bump"><float name="weight" value="0.5"/><bsdf type="diffuse"/></bsdf>
<bsdf type="diffuse" id="extra"><float name="roughness" value="0.5"/></bsdf>
<bsdf type="diffuse" id="unused"/>
<shape type="cube"><ref id="p"/></shape>
<shape type="cube"><ref id="rp"/></shape>
<shape type="cube"><ref id="thin"/></shape>
<shape type="cube"><ref id="n"/></shape>
<shape type="cube"><ref id="h"/></shape>
<shape type="cube"><ref id="bump"/></shape>
<shape type="cube"><ref id="extra"/><ref name="interior" id="fog"/></shape>
<shape type="serialized"><string name="filename" value="x.serialized"/></shape>
<shape type="sphere"><emitter type="area"><rgb name="radiance" value="1"/><float name="sampling_weight" value="2"/></emitter></shape>
<emitter type="projector"/>
<emitter type="point"><rgb name="intensity" value="1"/><float name="bogus" value="1"/></emitter>
<shape type="cube"><spectrum name="weird" value="400:0.1, 500:0.2"/></shape>
)");
    const char* expected[] = {
        "integrator: integrator 'volpath' is not supported",
        "integrator: hide_emitters is not supported",
        "integrator: parameter 'samples_per_pass' (<integer>) is not supported and was ignored",
        "sensor: sensor 'radiancemeter' is not supported",
        "sensor: parameter 'focal_length' (<string>) is not supported",
        "sensor.sampler: sampler 'stratified' is replaced",
        "sensor.film: film 'specfilm' is not supported",
        "sensor.film: pixel_format 'luminance' is not supported",
        "sensor.film: parameter 'banner' (<boolean>) is not supported",
        "sensor.film.rfilter: reconstruction filter 'mitchell' is not supported",
        "medium: <medium type=\"homogeneous\"> is not supported and was ignored",
        "bsdf(n): the null BSDF",
        "bsdf(h): BSDF 'hair' is not supported; using a grey diffuse",
        "bsdf(bump): BSDF 'blendbsdf' is not supported; using its nested BSDF",
        "bsdf(extra): parameter 'roughness' (<float>) is not supported",
        "bsdf(unused): never used by any shape",
        "shape[6]: parameter 'interior' (<ref>) is not supported and was ignored",
        "shape[7]: shape 'serialized' is not supported; it was skipped",
        "shape[8].emitter: sampling_weight is ignored",
        "emitter[0]: emitter 'projector' is not supported; it was skipped",
        "emitter[1]: parameter 'bogus' (<float>) is not supported",
        "shape[9]: parameter 'weird' (<spectrum>) is not supported",
    };
    for (const char* w : expected) EXPECT_TRUE(has_warning(d, w)) << w << "\nin:\n" << all_warnings(d);
    EXPECT_EQ(d.warnings.size(), std::size(expected)) << all_warnings(d);
    // The approximations themselves.
    // Plastic is supported now: no warning, and the coat is kept.
    expect_rgb(std::get<PlasticBsdf>(d.materials.at("p").bsdf).diffuse_reflectance, 0.2f, 0.2f, 0.2f);
    EXPECT_GT(std::get<PlasticBsdf>(d.materials.at("rp").bsdf).alpha, 0.f);
    EXPECT_TRUE(std::holds_alternative<ThinDielectricBsdf>(d.materials.at("thin").bsdf));  // supported now
    EXPECT_TRUE(std::holds_alternative<BlackBsdf>(d.materials.at("n").bsdf));
    EXPECT_EQ(d.integrator.type, IntegratorType::Path);
    EXPECT_EQ(d.sensor.halt.spp, 16);
    expect_round_trip(d);
}

TEST(MitsubaImporter, MalformedXmlIsASceneErrorWithItsLine) {
    EXPECT_EQ(scene_error_of([] { import_mitsuba_string("<scene>\n<shape type=\"cube\">\n</scene>\n", "bad.xml"); }),
              "bad.xml:3: invalid XML: Start-end tags mismatch");
    EXPECT_EQ(scene_error_of([] { import_mitsuba_string("<notascene/>", "bad.xml"); }),
              "bad.xml:1: scene: the root element must be <scene>");
    EXPECT_EQ(scene_error_of([] { import_mitsuba_string("\n\n<scene><shape type=\"cube\"", "bad.xml"); }).substr(0, 10),
              "bad.xml:3:");
    EXPECT_EQ(scene_error_of([] { import_mitsuba_file("/nonexistent/scene.xml"); }),
              "/nonexistent/scene.xml: cannot open the scene file");
}

TEST(MitsubaImporter, LoadSceneFileDispatchesOnExtension) {
    EXPECT_TRUE(is_mitsuba_path("a/b/Scene.XML"));
    EXPECT_FALSE(is_mitsuba_path("scene.yaml"));
    MitsubaOptions opt;
    opt.defines = {{"x", "1"}};
    EXPECT_EQ(scene_error_of([&] { load_scene_file("scene.yaml", opt); }),
              "scene.yaml: -D x=...: defines only apply to Mitsuba XML scenes");
}
