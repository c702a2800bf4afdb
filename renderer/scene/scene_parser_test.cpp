#include "scene/scene_parser.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "bsdf/metals.h"
#include "scene/scene_writer.h"
#include "scene/test_helpers.h"

using namespace omega;
using omega::test::scene_error_of;
using omega::test::source_root;
using omega::test::TempDir;


namespace {

void expect_near(const Mat4& a, const Mat4& b, double eps = 1e-12) {
    for (int i = 0; i < 16; ++i) EXPECT_NEAR(a.m[size_t(i)], b.m[size_t(i)], eps) << "element " << i;
}

std::string parse_error(const std::string& yaml) {
    return scene_error_of([&] { parse_scene_string(yaml, "scene.yaml"); });
}

}  // namespace

TEST(SceneParser, CornellBoxParses) {
    SceneDesc d = parse_scene_file((source_root() / "scenes/cornell-box.yaml").string());
    EXPECT_EQ(d.integrator.type, IntegratorType::Path);
    EXPECT_EQ(d.integrator.max_depth, 65);
    EXPECT_EQ(d.sensor.film.width, 1024);
    EXPECT_EQ(d.sensor.film.height, 1024);
    EXPECT_EQ(d.sensor.film.filter, FilterType::Tent);
    EXPECT_FLOAT_EQ(d.sensor.fov, 19.5f);
    EXPECT_EQ(d.sensor.to_world(2, 3), 6.8);
    EXPECT_EQ(d.sensor.to_world(0, 0), -1);
    ASSERT_EQ(d.shapes.size(), 8u);
    EXPECT_EQ(d.materials.size(), 8u);
    EXPECT_TRUE(d.warnings.empty()) << d.warnings[0];
    const ShapeDesc& light = d.shapes[7];
    EXPECT_EQ(light.name, "Light");
    ASSERT_TRUE(light.emitter);
    EXPECT_EQ(light.emitter->radiance, (Rgb{17, 12, 4}));
    EXPECT_FALSE(light.emitter->two_sided);
    EXPECT_DOUBLE_EQ(light.to_world(1, 3), 1.98);
    // The light faces down.
    Transform t = *Transform::make(light.to_world);
    EXPECT_LT(t.normal({0, 0, 1}).y, 0);
    EXPECT_EQ(d.shapes[5].type, ShapeType::Cube);
    auto& left = std::get<DiffuseBsdf>(d.materials.at("LeftWallBSDF").bsdf);
    EXPECT_EQ(left.reflectance, (Rgb{0.63f, 0.065f, 0.05f}));
    EXPECT_TRUE(left.two_sided);
}

TEST(SceneParser, VeachMisParses) {
    SceneDesc d = parse_scene_file((source_root() / "scenes/veach-mis.yaml").string());
    // TungstenRender.exr is direct lighting only (docs/scene-format.md, importer section).
    EXPECT_EQ(d.integrator.max_depth, 2);
    EXPECT_EQ(d.sensor.film.width, 1280);
    EXPECT_EQ(d.sensor.film.height, 720);
    ASSERT_EQ(d.shapes.size(), 9u);
    EXPECT_TRUE(d.warnings.empty());
    auto& c = std::get<ConductorBsdf>(d.materials.at("GlossyBSDF").bsdf);
    EXPECT_TRUE(c.has_ior);
    EXPECT_EQ(c.distribution, MicrofacetType::Beckmann);
    EXPECT_FLOAT_EQ(c.alpha_u, 0.05f);
    EXPECT_FLOAT_EQ(c.alpha_v, 0.05f);
    EXPECT_EQ(c.specular_reflectance, (Rgb{0.3f, 0.3f, 0.3f}));
    EXPECT_FLOAT_EQ(c.k.x, 3.91295f);
    const ShapeDesc& s = d.shapes[7];
    EXPECT_EQ(s.type, ShapeType::Sphere);
    EXPECT_DOUBLE_EQ(s.radius, 0.05);
    EXPECT_EQ(s.center, (Vec3d{0, 6.5, 2.7}));
    EXPECT_FLOAT_EQ(s.emitter->radiance.x, 3039.64f);
}

TEST(SceneParser, EveryKeyRoundTrips) {
    TempDir dir;
    dir.write("meshes/tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    std::string yaml = R"(omega: 1
integrator: {type: bdpt, max_depth: -1, rr_depth: 3}
sensor:
  type: thin_lens
  fov: 30
  fov_axis: y
  aperture_radius: 0.1
  focus_distance: 4
  near_clip: 0.01
  to_world: {look_at: {origin: [0, 1, 6.8], target: [0, 1, 0], up: [0, 1, 0]}}
  film: {width: 64, height: 32, filter: gaussian, stddev: 0.25, crop: [1, 2, 63, 30]}
  spp: 16
  time: 2.5
  target_error: 0.01
materials:
  white: {type: diffuse, reflectance: 0.5, two_sided: false}
  gold: {type: conductor, material: Au, alpha_u: 0.1, alpha_v: 0.2, distribution: beckmann, specular_reflectance: [1, 0.9, 0.8], two_sided: false}
  cu: {type: conductor, eta: [0.2, 0.9, 1.1], k: [3.9, 2.4, 2.1]}
  mirror: {type: conductor}
  glass: {type: dielectric, int_ior: diamond, ext_ior: water, alpha: 0.05, distribution: ggx, specular_reflectance: 0.9, specular_transmittance: [1, 1, 0.5]}
  glass2: {type: dielectric, int_ior: 1.5, ext_ior: 1}
  dark: {type: black}
shapes:
  - {type: mesh, file: meshes/tri.obj, face_normals: true, drop_degenerate: true, material: white, flip_normals: true}
  - {type: rectangle, material: gold, emitter: {type: area, radiance: [1, 2, 3], two_sided: true}}
  - {type: cube, material: cu, to_world: {scale: 2}}
  - {type: sphere, center: [1, 2, 3], radius: 0.5, material: mirror}
  - {type: disk, material: glass, to_world: {translate: [0, 0, 1]}}
  - {type: disk, material: glass2}
  - {type: disk, material: dark}
  - {type: disk, material: {type: diffuse, reflectance: [0.1, 0.2, 0.3]}}
  - {type: disk, name: plain}
lights:
  - {type: point, position: [0, 1.9, 0], intensity: [5, 5, 5]}
  - {type: spot, to_world: {look_at: {origin: [0, 2, 0], target: [0, 0, 0], up: [0, 0, 1]}}, intensity: 10, cutoff_angle: 30}
  - {type: spot, intensity: 1, cutoff_angle: 40, beam_width: 20}
  - {type: directional, direction: [0, -2, 0], irradiance: [1, 1, 1]}
  - {type: constant, radiance: [0.1, 0.2, 0.3]}
)";
    std::string path = dir.write("scene.yaml", yaml).string();
    SceneDesc d = parse_scene_file(path);
    EXPECT_EQ(d.path, path);
    EXPECT_EQ(d.integrator.type, IntegratorType::Bdpt);
    EXPECT_EQ(d.integrator.max_depth, -1);
    EXPECT_EQ(d.integrator.rr_depth, 3);
    const SensorDesc& s = d.sensor;
    EXPECT_EQ(s.type, SensorType::ThinLens);
    EXPECT_EQ(s.fov, 30.f);
    EXPECT_EQ(s.fov_axis, 'y');
    EXPECT_FLOAT_EQ(s.aperture_radius, 0.1f);
    EXPECT_FLOAT_EQ(s.focus_distance, 4.f);
    EXPECT_FLOAT_EQ(s.near_clip, 0.01f);
    expect_near(s.to_world, Mat4::look_at({0, 1, 6.8}, {0, 1, 0}, {0, 1, 0}));
    EXPECT_EQ(s.loc.line, 4);
    EXPECT_EQ(s.film.width, 64);
    EXPECT_EQ(s.film.height, 32);
    EXPECT_EQ(s.film.filter, FilterType::Gaussian);
    EXPECT_FLOAT_EQ(s.film.gaussian_stddev, 0.25f);
    EXPECT_FLOAT_EQ(s.film.filter_radius, 1.f);
    EXPECT_TRUE(s.film.has_crop);
    EXPECT_EQ(s.film.crop, (std::array<int, 4>{1, 2, 63, 30}));
    EXPECT_EQ(s.halt.spp, 16);
    EXPECT_EQ(s.halt.time_s, 2.5);
    EXPECT_EQ(s.halt.target_error, 0.01);

    auto& white = std::get<DiffuseBsdf>(d.materials.at("white").bsdf);
    EXPECT_EQ(white.reflectance, (Rgb{0.5f, 0.5f, 0.5f}));
    EXPECT_FALSE(white.two_sided);
    EXPECT_EQ(d.materials.at("white").loc.line, 16);
    EXPECT_EQ(d.materials.at("white").loc.key, "materials.white");
    auto& gold = std::get<ConductorBsdf>(d.materials.at("gold").bsdf);
    EXPECT_TRUE(gold.has_ior);
    EXPECT_EQ(gold.eta, named_metal_ior("Au")->first);
    EXPECT_FLOAT_EQ(gold.alpha_u, 0.1f);
    EXPECT_FLOAT_EQ(gold.alpha_v, 0.2f);
    EXPECT_EQ(gold.distribution, MicrofacetType::Beckmann);
    EXPECT_EQ(gold.specular_reflectance, (Rgb{1, 0.9f, 0.8f}));
    EXPECT_FALSE(gold.two_sided);
    auto& cu = std::get<ConductorBsdf>(d.materials.at("cu").bsdf);
    EXPECT_TRUE(cu.has_ior);
    EXPECT_EQ(cu.k, (Rgb{3.9f, 2.4f, 2.1f}));
    EXPECT_EQ(cu.alpha_u, 0.f);
    auto& mirror = std::get<ConductorBsdf>(d.materials.at("mirror").bsdf);
    EXPECT_FALSE(mirror.has_ior);
    EXPECT_EQ(mirror.distribution, MicrofacetType::GGX);
    auto& glass = std::get<DielectricBsdf>(d.materials.at("glass").bsdf);
    EXPECT_FLOAT_EQ(glass.eta, 2.419f / 1.333f);
    EXPECT_FLOAT_EQ(glass.alpha_u, 0.05f);
    EXPECT_EQ(glass.specular_reflectance, (Rgb{0.9f, 0.9f, 0.9f}));
    EXPECT_EQ(glass.specular_transmittance, (Rgb{1, 1, 0.5f}));
    EXPECT_FLOAT_EQ(std::get<DielectricBsdf>(d.materials.at("glass2").bsdf).eta, 1.5f);
    EXPECT_TRUE(std::holds_alternative<BlackBsdf>(d.materials.at("dark").bsdf));

    ASSERT_EQ(d.shapes.size(), 9u);
    const ShapeDesc& mesh = d.shapes[0];
    EXPECT_EQ(mesh.type, ShapeType::Mesh);
    EXPECT_EQ(mesh.file, (dir.path / "meshes/tri.obj").lexically_normal().string());
    EXPECT_TRUE(mesh.face_normals);
    EXPECT_TRUE(mesh.drop_degenerate);
    EXPECT_TRUE(mesh.flip_normals);
    EXPECT_EQ(mesh.material, "white");
    EXPECT_EQ(mesh.loc.line, 24);
    EXPECT_EQ(mesh.loc.key, "shapes[0]");
    ASSERT_TRUE(d.shapes[1].emitter);
    EXPECT_EQ(d.shapes[1].emitter->radiance, (Rgb{1, 2, 3}));
    EXPECT_TRUE(d.shapes[1].emitter->two_sided);
    EXPECT_FALSE(d.shapes[2].emitter);
    expect_near(d.shapes[2].to_world, Mat4::scale({2, 2, 2}));
    EXPECT_EQ(d.shapes[3].center, (Vec3d{1, 2, 3}));
    EXPECT_EQ(d.shapes[3].radius, 0.5);
    expect_near(d.shapes[4].to_world, Mat4::translate({0, 0, 1}));
    EXPECT_EQ(d.shapes[4].type, ShapeType::Disk);
    // Inline and default materials get internal names that a file cannot reference by accident.
    const std::string& inl = d.shapes[7].material;
    EXPECT_EQ(inl, "shapes[7].material");
    EXPECT_EQ(std::get<DiffuseBsdf>(d.materials.at(inl).bsdf).reflectance, (Rgb{0.1f, 0.2f, 0.3f}));
    EXPECT_EQ(d.shapes[8].name, "plain");
    EXPECT_EQ(std::get<DiffuseBsdf>(d.materials.at(d.shapes[8].material).bsdf).reflectance, (Rgb{0.5f, 0.5f, 0.5f}));

    ASSERT_EQ(d.lights.size(), 5u);
    EXPECT_EQ(d.lights[0].type, LightType::Point);
    EXPECT_EQ(d.lights[0].position, (Vec3d{0, 1.9, 0}));
    EXPECT_EQ(d.lights[0].intensity, (Rgb{5, 5, 5}));
    EXPECT_EQ(d.lights[1].type, LightType::Spot);
    EXPECT_EQ(d.lights[1].cutoff_angle, 30.f);
    EXPECT_EQ(d.lights[1].beam_width, 22.5f);  // 3/4 of the cutoff
    EXPECT_EQ(d.lights[1].intensity, (Rgb{10, 10, 10}));
    expect_near(d.lights[1].to_world, Mat4::look_at({0, 2, 0}, {0, 0, 0}, {0, 0, 1}));
    EXPECT_EQ(d.lights[2].beam_width, 20.f);
    EXPECT_EQ(d.lights[3].direction, (Vec3d{0, -1, 0}));
    EXPECT_EQ(d.lights[3].irradiance, (Rgb{1, 1, 1}));
    EXPECT_EQ(d.lights[4].type, LightType::Constant);
    EXPECT_EQ(d.lights[4].radiance, (Rgb{0.1f, 0.2f, 0.3f}));
    EXPECT_TRUE(d.warnings.empty()) << d.warnings[0];
}

TEST(SceneParser, Defaults) {
    SceneDesc d = parse_scene_string("omega: 1\nlights: [{type: constant, radiance: 1}]\n", "scene.yaml");
    EXPECT_EQ(d.integrator.type, IntegratorType::Path);
    EXPECT_EQ(d.integrator.max_depth, -1);
    EXPECT_EQ(d.sensor.type, SensorType::Perspective);
    EXPECT_EQ(d.sensor.film.width, 512);
    EXPECT_FALSE(d.sensor.film.has_crop);
    EXPECT_EQ(d.sensor.film.crop, (std::array<int, 4>{0, 0, 512, 512}));
    EXPECT_FALSE(d.sensor.halt.spp);
    EXPECT_TRUE(d.shapes.empty());
    EXPECT_TRUE(d.warnings.empty());
}

TEST(SceneParser, PlasticDefaultsAndNamedIors) {
    SceneDesc d = parse_scene_string(R"(omega: 1
lights: [{type: constant, radiance: 1}]
materials:
  p: {type: plastic}
  r: {type: roughplastic, int_ior: bk7, ext_ior: water, diffuse_reflectance: [0.1, 0.2, 0.3],
      specular_reflectance: 0.5, nonlinear: true, distribution: beckmann, two_sided: false}
  s: {type: roughplastic}
)", "scene.yaml");
    const auto& p = std::get<PlasticBsdf>(d.materials.at("p").bsdf);
    EXPECT_FLOAT_EQ(p.eta, 1.49f / 1.000277f);  // Mitsuba's polypropylene in air
    EXPECT_EQ(p.fdr_int, plastic_fdr_int(p.eta));
    EXPECT_EQ(p.diffuse_reflectance, Rgb(0.5f));
    EXPECT_EQ(p.specular_reflectance, Rgb(1.f));
    EXPECT_FALSE(p.nonlinear);
    EXPECT_EQ(p.alpha, 0.f);
    EXPECT_TRUE(p.two_sided);
    const auto& r = std::get<PlasticBsdf>(d.materials.at("r").bsdf);
    EXPECT_FLOAT_EQ(r.eta, 1.5046f / 1.333f);
    EXPECT_EQ(r.fdr_int, plastic_fdr_int(r.eta));
    EXPECT_EQ(r.diffuse_reflectance, (Rgb{0.1f, 0.2f, 0.3f}));
    EXPECT_EQ(r.specular_reflectance, Rgb(0.5f));
    EXPECT_TRUE(r.nonlinear);
    EXPECT_EQ(r.distribution, MicrofacetType::Beckmann);
    EXPECT_FALSE(r.two_sided);
    const auto& s = std::get<PlasticBsdf>(d.materials.at("s").bsdf);
    EXPECT_FLOAT_EQ(s.alpha, 0.1f);
    EXPECT_EQ(s.distribution, MicrofacetType::GGX);  // Omega's format default, as for conductors
}

TEST(SceneParser, ToWorldOrder) {
    // The first operation applies to the points first: translate-then-rotate moves (1,0,0) to
    // (2,0,0) and then turns it to (0,2,0); rotate-then-translate gives (1,1,0).
    auto m_of = [](const std::string& tw) {
        SceneDesc d = parse_scene_string("omega: 1\nshapes:\n  - {type: cube, to_world: " + tw + "}\n", "scene.yaml");
        return d.shapes[0].to_world;
    };
    Mat4 tr = m_of("[{translate: [1, 0, 0]}, {rotate: {axis: [0, 0, 1], angle: 90}}]");
    Mat4 rt = m_of("[{rotate: {axis: [0, 0, 1], angle: 90}}, {translate: [1, 0, 0]}]");
    expect_near(tr, Mat4::rotate({0, 0, 1}, 90) * Mat4::translate({1, 0, 0}));
    expect_near(rt, Mat4::translate({1, 0, 0}) * Mat4::rotate({0, 0, 1}, 90));
    Vec3d a = tr.point({1, 0, 0}), b = rt.point({1, 0, 0});
    EXPECT_NEAR(a.x, 0, 1e-12);
    EXPECT_NEAR(a.y, 2, 1e-12);
    EXPECT_NEAR(b.x, 1, 1e-12);
    EXPECT_NEAR(b.y, 1, 1e-12);
    // scale by vector, single mapping, and a matrix inside a list.
    expect_near(m_of("{scale: [1, 2, 3]}"), Mat4::scale({1, 2, 3}));
    expect_near(m_of("[{scale: 2}, {matrix: [1,0,0,5, 0,1,0,0, 0,0,1,0, 0,0,0,1]}]"),
                Mat4::translate({5, 0, 0}) * Mat4::scale({2, 2, 2}));
    Mat4 rm = m_of("{matrix: [1, 2, 3, 4, 0, 1, 0, 5, 0, 0, 1, 6, 0, 0, 0, 1]}");
    EXPECT_EQ(rm(0, 1), 2);  // row-major
    EXPECT_EQ(rm(2, 3), 6);
}

TEST(SceneParser, Errors) {
    // Malformed YAML reports yaml-cpp's line.
    EXPECT_EQ(parse_error("omega: 1\nsensor:\n  fov: [1, 2\n").substr(0, 13), "scene.yaml:4:");
    EXPECT_NE(parse_error("omega: 1\nsensor: {fov: 1\n").find("invalid YAML"), std::string::npos);
    EXPECT_EQ(parse_error("omega: 1\na: b: c\n").substr(0, 13), "scene.yaml:2:");
    // Version.
    EXPECT_EQ(parse_error("sensor: {}\n"), "scene.yaml:1: omega: missing key (a v1 scene starts with 'omega: 1')");
    EXPECT_EQ(parse_error("omega: 2\n"),
              "scene.yaml:1: omega: unsupported scene format version 2 (this build reads version 1)");
    EXPECT_EQ(parse_error(""), "scene.yaml:1: expected a mapping, got nothing");
    EXPECT_EQ(parse_error("- 1\n"), "scene.yaml:1: expected a mapping, got a list");
    // Unknown keys, top level and nested.
    EXPECT_EQ(parse_error("omega: 1\nintegrater: {type: path}\n"), "scene.yaml:2: integrater: unknown key");
    EXPECT_EQ(parse_error("omega: 1\nmaterials:\n  white:\n    type: diffuse\n    reflectanse: 0.5\n"),
              "scene.yaml:5: materials.white.reflectanse: unknown key");
    EXPECT_EQ(parse_error("omega: 1\nsensor:\n  film: {width: 10, hieght: 10}\n"),
              "scene.yaml:3: sensor.film.hieght: unknown key");
    EXPECT_EQ(parse_error("omega: 1\nshapes:\n  - type: cube\n  - type: sphere\n    radius: 1\n    raduis: 2\n"),
              "scene.yaml:6: shapes[1].raduis: unknown key");
    // Keys of another variant.
    EXPECT_EQ(parse_error("omega: 1\nshapes:\n  - {type: cube, radius: 1}\n"),
              "scene.yaml:3: shapes[0].radius: not used by this shape type (only sphere)");
    // Wrong types and bad values.
    EXPECT_EQ(parse_error("omega: 1\nsensor:\n  fov: abc\n"), "scene.yaml:3: sensor.fov: expected a number, got 'abc'");
    EXPECT_EQ(parse_error("omega: 1\nsensor:\n  fov: 180\n"), "scene.yaml:3: sensor.fov: must be in (0, 180), got 180");
    EXPECT_EQ(parse_error("omega: 1\nsensor:\n  film: {width: 0}\n"),
              "scene.yaml:3: sensor.film.width: must be in [1, 65536], got 0");
    EXPECT_EQ(parse_error("omega: 1\nsensor:\n  film: {width: 10, height: 10, crop: [0, 0, 11, 10]}\n"),
              "scene.yaml:3: sensor.film.crop: must satisfy 0 <= x0 < x1 <= width (10) and 0 <= y0 < y1 <= height (10), "
              "got [0, 0, 11, 10]");
    EXPECT_EQ(parse_error("omega: 1\nshapes:\n  - {type: sphere, radius: -1}\n"),
              "scene.yaml:3: shapes[0].radius: must be > 0, got -1");
    EXPECT_EQ(parse_error("omega: 1\nmaterials:\n  w: {type: diffuse, reflectance: [0.5, 1.2, 0]}\n"),
              "scene.yaml:3: materials.w.reflectance: components must be in [0, 1], got [0.5, 1.2, 0]");
    EXPECT_EQ(parse_error("omega: 1\nmaterials:\n  w: {type: velvet}\n"),
              "scene.yaml:3: materials.w.type: expected one of diffuse, roughdiffuse, conductor, dielectric, thindielectric, "
              "plastic, roughplastic, black, got 'velvet'");
    // Plastic is isotropic (as in Mitsuba and Tungsten), and a smooth plastic has no roughness.
    EXPECT_NE(parse_error("omega: 1\nmaterials:\n  p: {type: roughplastic, alpha_u: 0.1, alpha_v: 0.2}\n").find("alpha_u"),
              std::string::npos);
    EXPECT_NE(parse_error("omega: 1\nmaterials:\n  p: {type: plastic, alpha: 0.1}\n").find("materials.p.alpha"),
              std::string::npos);
    EXPECT_NE(parse_error("omega: 1\nmaterials:\n  p: {type: plastic, int_ior: unobtainium}\n").find("materials.p.int_ior"),
              std::string::npos);
    EXPECT_EQ(parse_error("omega: 1\nmaterials:\n  g: {type: dielectric, int_ior: unobtainium}\n"),
              "scene.yaml:3: materials.g.int_ior: expected a number or a named IOR (vacuum, air, water, bk7, glass, "
              "diamond, ...), got 'unobtainium'");
    EXPECT_EQ(parse_error("omega: 1\nmaterials:\n  m: {type: conductor, material: Xx}\n"),
              "scene.yaml:3: materials.m.material: unknown metal 'Xx' (known: Au, Ag, Cu, Al)");
    EXPECT_EQ(parse_error("omega: 1\nmaterials:\n  m: {type: conductor, eta: 1}\n"),
              "scene.yaml:3: materials.m.k: missing key");
    EXPECT_EQ(parse_error("omega: 1\nintegrator: {max_depth: 0}\n"),
              "scene.yaml:2: integrator.max_depth: must be -1 (unbounded) or >= 1, got 0");
    EXPECT_EQ(parse_error("omega: 1\nshapes: {type: cube}\n"), "scene.yaml:2: shapes: expected a list, got a mapping");
    EXPECT_EQ(parse_error("omega: 1\nshapes:\n  - {type: rectangle, emitter: {type: area}}\n"),
              "scene.yaml:3: shapes[0].emitter.radiance: missing key");
    // Unknown material reference.
    EXPECT_EQ(parse_error("omega: 1\nmaterials:\n  white: {type: diffuse}\nshapes:\n  - type: cube\n    material: whte\n"),
              "scene.yaml:6: shapes[0].material: unknown material 'whte'");
    // Transforms: NaN, singular, projective, unknown operation.
    EXPECT_EQ(parse_error("omega: 1\nshapes:\n  - type: cube\n    to_world: {matrix: [1,0,0,0, 0,.nan,0,0, 0,0,1,0, "
                          "0,0,0,1]}\n"),
              "scene.yaml:4: shapes[0].to_world.matrix[5]: expected a finite number, got '.nan'");
    EXPECT_EQ(parse_error("omega: 1\nshapes:\n  - type: cube\n    to_world: {matrix: [1,0,0,0, 0,0,0,0, 0,0,1,0, "
                          "0,0,0,1]}\n"),
              "scene.yaml:4: shapes[0].to_world: matrix is singular");
    EXPECT_EQ(parse_error("omega: 1\nshapes:\n  - type: cube\n    to_world: [{scale: 0}]\n"),
              "scene.yaml:4: shapes[0].to_world: matrix is singular");
    EXPECT_EQ(parse_error("omega: 1\nsensor:\n  to_world: {matrix: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,1]}\n"),
              "scene.yaml:3: sensor.to_world: last row must be [0, 0, 0, 1] (an affine transform)");
    EXPECT_EQ(parse_error("omega: 1\nshapes:\n  - type: cube\n    to_world: [{translat: [1, 0, 0]}]\n"),
              "scene.yaml:4: shapes[0].to_world[0].translat: unknown key");
    EXPECT_EQ(parse_error("omega: 1\nshapes:\n  - type: cube\n    to_world: {translate: [1, 0, 0], scale: 2}\n"),
              "scene.yaml:4: shapes[0].to_world: expected exactly one of matrix, look_at, translate, rotate, scale "
              "(use a list to combine them)");
    EXPECT_EQ(parse_error("omega: 1\nsensor:\n  to_world: {look_at: {origin: [0, 0, 0], target: [0, 1, 0], up: [0, 1, 0]}}\n"),
              "scene.yaml:3: sensor.to_world.look_at: up must not be zero or parallel to the view direction");
    EXPECT_EQ(parse_error("omega: 1\nshapes:\n  - type: cube\n    to_world: {scale: [1e300, 1e300, 1e300]}\n"
                          "    material: {type: black}\n").substr(0, 26),
              "scene.yaml:4: shapes[0].to");
}

TEST(SceneParser, MissingMeshFile) {
    TempDir dir;
    std::string yaml = "omega: 1\nshapes:\n  - type: cube\n  - type: cube\n  - type: cube\n  - type: mesh\n"
                       "    file: meshes/x.obj\n";
    std::string path = dir.write("scene.yaml", yaml).string();
    EXPECT_EQ(scene_error_of([&] { parse_scene_file(path); }),
              path + ":7: shapes[3].file: cannot open 'meshes/x.obj': No such file or directory");
    // A folder is not a mesh file either.
    std::filesystem::create_directories(dir.path / "meshes/x.obj");
    EXPECT_EQ(scene_error_of([&] { parse_scene_file(path); }),
              path + ":7: shapes[3].file: cannot open 'meshes/x.obj': not a regular file");
    EXPECT_EQ(scene_error_of([&] { parse_scene_file((dir.path / "nope.yaml").string()); }),
              (dir.path / "nope.yaml").string() + ": cannot open the scene file");
}

TEST(SceneParser, Warnings) {
    SceneDesc d = parse_scene_string(
        "omega: 1\nmaterials:\n  used: {type: diffuse}\n  unused: {type: diffuse}\nshapes:\n  - {type: cube, material: used}\n",
        "scene.yaml");
    ASSERT_EQ(d.warnings.size(), 2u);
    EXPECT_EQ(d.warnings[0], "scene.yaml:4: materials.unused: never used by any shape");
    EXPECT_EQ(d.warnings[1], "scene.yaml:1: the scene has no light source; the image will be black");
}

TEST(SceneParser, DocumentationExampleParses) {
    std::ifstream in(source_root() / "docs/scene-format.md");
    std::stringstream ss;
    ss << in.rdbuf();
    std::string doc = ss.str();
    size_t start = doc.find("```yaml\n");
    ASSERT_NE(start, std::string::npos);
    start += 8;
    std::string yaml = doc.substr(start, doc.find("```", start) - start);
    TempDir dir;
    dir.write("meshes/bunny.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    SceneDesc d = parse_scene_file(dir.write("scene.yaml", yaml).string());
    EXPECT_EQ(d.shapes.size(), 5u);
    EXPECT_EQ(d.lights.size(), 1u);
    EXPECT_TRUE(d.warnings.empty()) << d.warnings[0];
}

TEST(SceneParser, SamplerKey) {
    const std::string light = "lights: [{type: constant, radiance: 1}]\n";
    EXPECT_EQ(parse_scene_string("omega: 1\n" + light, "scene.yaml").integrator.sampler, SamplerType::Sobol);
    EXPECT_EQ(parse_scene_string("omega: 1\nsampler: {type: independent}\n" + light, "scene.yaml").integrator.sampler,
              SamplerType::Independent);
    EXPECT_EQ(parse_scene_string("omega: 1\nsampler: {type: sobol}\n" + light, "scene.yaml").integrator.sampler,
              SamplerType::Sobol);
    EXPECT_NE(parse_error("omega: 1\nsampler: {type: halton}\n").find("scene.yaml:2: sampler.type:"), std::string::npos);
    EXPECT_EQ(parse_error("omega: 1\nsampler: {type: sobol, seed: 3}\n"), "scene.yaml:2: sampler.seed: unknown key");
}

TEST(SceneParser, FilmAovs) {
    const std::string light = "lights: [{type: point, position: [0, 1, 0], intensity: 1}]\n";
    SceneDesc d = parse_scene_string(
        "omega: 1\nsensor:\n  film: {width: 8, height: 8, aov: {caustics: \"L S+ D E\", direct: L D E}}\n" + light,
        "scene.yaml");
    ASSERT_EQ(d.sensor.film.aovs.size(), 2u);
    EXPECT_EQ(d.sensor.film.aovs[0], (AovDesc{"caustics", "L S+ D E"}));
    EXPECT_EQ(d.sensor.film.aovs[1], (AovDesc{"direct", "L D E"}));
    // Written back and read again: the same AOVs, in the same order.
    SceneDesc again = parse_scene_string(write_scene_yaml(d), "again.yaml");
    EXPECT_EQ(again.sensor.film.aovs, d.sensor.film.aovs);
    // Errors name the line and key, the column of the expression, the bad name.
    const std::string bad_expr = parse_error("omega: 1\nsensor:\n  film:\n    aov: {x: \"L ( E\"}\n" + light);
    EXPECT_NE(bad_expr.find("scene.yaml:4:"), std::string::npos) << bad_expr;
    EXPECT_NE(bad_expr.find("column 6: expected ')'"), std::string::npos) << bad_expr;
    const std::string bad_name = parse_error("omega: 1\nsensor:\n  film:\n    aov: {\"a-b\": \"L E\"}\n" + light);
    EXPECT_NE(bad_name.find("aov name 'a-b'"), std::string::npos) << bad_name;
    EXPECT_NE(parse_error("omega: 1\nsensor:\n  film: {aov: [L E]}\n" + light).find("expected a mapping"),
              std::string::npos);
}
