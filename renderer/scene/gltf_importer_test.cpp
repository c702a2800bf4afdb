// The glTF importer on what Blender's own exporter writes (tests/data/gltf, made by
// tests/data/gltf/make_scene.py with Blender 3.4.1) and on small hand-written files.
#include "scene/gltf_importer.h"

#include <gtest/gtest.h>

#include <cmath>

#include "io/file_gate.h"
#include "scene/mitsuba_importer.h"
#include "scene/scene.h"
#include "scene/scene_parser.h"
#include "scene/scene_writer.h"
#include "scene/test_helpers.h"
#include "scene/triangle_mesh.h"

using namespace omega;
using omega::test::scene_error_of;
using omega::test::TempDir;
using omega::test::all_warnings;
using omega::test::has_warning;

namespace {

constexpr double kDegPi = 3.14159265358979323846;

std::string blender_file(const std::string& name) {
    return (test::source_root() / "tests/data/gltf" / name).string();
}
Vec3d column(const Mat4& m, int c) { return {m(0, c), m(1, c), m(2, c)}; }
double length(const Vec3d& v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }
void expect_vec(const Vec3d& a, const Vec3d& b, double eps) {
    EXPECT_NEAR(a.x, b.x, eps);
    EXPECT_NEAR(a.y, b.y, eps);
    EXPECT_NEAR(a.z, b.z, eps);
}
void expect_rgb_near(const Rgb& a, double r, double g, double b, double rel = 1e-5) {
    EXPECT_NEAR(a.x, r, rel * std::max(1.0, r));
    EXPECT_NEAR(a.y, g, rel * std::max(1.0, g));
    EXPECT_NEAR(a.z, b, rel * std::max(1.0, b));
}
const LightDesc* light_of(const SceneDesc& d, LightType t) {
    for (const auto& l : d.lights)
        if (l.type == t) return &l;
    return nullptr;
}

// A one-triangle glTF (positions in a data: uri) with the given extra top-level JSON members.
std::string tiny_gltf(const std::string& extra, const std::string& buffer_uri =
                                                      "data:application/octet-stream;base64,"
                                                      "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA") {
    return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
  "materials": [{"name": "M", "emissiveFactor": [1, 1, 1]}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}],
  "buffers": [{"byteLength": 36, "uri": ")" +
           buffer_uri + "\"}]" + extra + "}";
}

}  // namespace

// Blender's default camera export: the first camera, placed by its node, vertical fov from yfov.
TEST(GltfImporter, BlenderCameraIsThePerspectiveOneAtItsNode) {
    SceneDesc d = import_gltf_file(blender_file("blender_scene.gltf"));
    EXPECT_EQ(d.sensor.type, SensorType::Perspective);
    EXPECT_EQ(d.sensor.fov_axis, 'y');
    // Blender: 50 degrees across a 4:3 frame -> 2 atan(tan 25 / (4/3)) = 38.55 degrees vertically.
    EXPECT_NEAR(d.sensor.fov, 2 * std::atan(std::tan(25 * kDegPi / 180) * 0.75) * 180 / kDegPi, 1e-3);
    EXPECT_EQ(d.sensor.film.width, 320);
    EXPECT_EQ(d.sensor.film.height, 240);
    // Blender location (0.5, -6, 3), z up -> glTF (0.5, 3, 6), y up.
    expect_vec(column(d.sensor.to_world, 3), {0.5, 3, 6}, 1e-5);
    // Blender rotation (68, 0, 4) degrees: looks along (-sin4 sin68, cos4 sin68, -cos68), in glTF axes.
    const double s68 = std::sin(68 * kDegPi / 180), c68 = std::cos(68 * kDegPi / 180);
    expect_vec(column(d.sensor.to_world, 2), {-std::sin(4 * kDegPi / 180) * s68, -c68, -std::cos(4 * kDegPi / 180) * s68}, 1e-5);
    // Omega's frame: +x is the image's left, +y up (so x = up x direction).
    expect_vec(column(d.sensor.to_world, 0), {-std::cos(4 * kDegPi / 180), 0, std::sin(4 * kDegPi / 180)}, 1e-5);
    EXPECT_NEAR(d.sensor.near_clip, 0.1, 1e-6);
}

TEST(GltfImporter, CameraByNameAndOrthographic) {
    GltfOptions opt;
    opt.camera = "TopCamera";
    SceneDesc d = import_gltf_file(blender_file("blender_scene.gltf"), opt);
    EXPECT_EQ(d.sensor.type, SensorType::Orthographic);
    // ortho_scale 6 -> xmag 3, ymag 3 / (4/3): the to_world scale is the half extent.
    EXPECT_NEAR(length(column(d.sensor.to_world, 0)), 3, 1e-5);
    EXPECT_NEAR(length(column(d.sensor.to_world, 1)), 2.25, 1e-5);
    expect_vec(column(d.sensor.to_world, 2), {0, -1, 0}, 1e-5);  // looks straight down
    expect_vec(column(d.sensor.to_world, 3), {0, 8, 0}, 1e-5);
    EXPECT_EQ(d.sensor.film.height, 240);

    opt.camera = "NoSuchCamera";
    std::string err = scene_error_of([&] { import_gltf_file(blender_file("blender_scene.gltf"), opt); });
    EXPECT_NE(err.find("--camera NoSuchCamera: no such camera"), std::string::npos) << err;
    EXPECT_NE(err.find("'MainCamera', 'TopCamera'"), std::string::npos) << err;
}

// KHR_lights_punctual from Blender's 'SPEC' lighting mode: W -> cd = W / 4 pi * 683, W/m^2 -> lux
// = W/m^2 * 683. Over 683 lm/W the importer gets Blender's W / 4 pi (W/sr) and W/m^2 back.
TEST(GltfImporter, BlenderLightsComeBackInWatts) {
    SceneDesc d = import_gltf_file(blender_file("blender_scene.gltf"));
    ASSERT_EQ(d.lights.size(), 3u);
    const LightDesc* p = light_of(d, LightType::Point);
    const LightDesc* s = light_of(d, LightType::Spot);
    const LightDesc* sun = light_of(d, LightType::Directional);
    ASSERT_TRUE(p && s && sun);
    const double point = 150 / (4 * kDegPi), spot = 400 / (4 * kDegPi);
    expect_rgb_near(p->intensity, point, point * 0.9, point * 0.8);
    expect_vec(p->position, {2, 2.5, 1.5}, 1e-5);
    expect_rgb_near(s->intensity, spot * 0.8, spot * 0.9, spot);
    EXPECT_NEAR(s->cutoff_angle, 25, 1e-3);           // Blender spot_size 50 degrees
    EXPECT_NEAR(s->beam_width, 25 * (1 - 0.3), 1e-3);  // spot_blend 0.3
    expect_vec(column(s->to_world, 3), {-2, 3, 2}, 1e-5);
    // Blender rotation (40, 0, -45): shines along (sin40 sin45, sin40 cos45, -cos40) in Blender axes.
    const double s40 = std::sin(40 * kDegPi / 180), c40 = std::cos(40 * kDegPi / 180), h = std::sqrt(0.5);
    expect_vec(column(s->to_world, 2), {s40 * h, -c40, -s40 * h}, 1e-5);
    expect_rgb_near(sun->irradiance, 1.5, 1.5, 1.5);
    // Rotation (30, 20, 0): (-cos30 sin20, sin30, -cos30 cos20) in Blender axes.
    const double c30 = std::cos(30 * kDegPi / 180), s20 = std::sin(20 * kDegPi / 180), c20 = std::cos(20 * kDegPi / 180);
    expect_vec(sun->direction, {-c30 * s20, -c30 * c20, -0.5}, 1e-5);
    EXPECT_TRUE(has_warning(d, "spot lights fall off")) << all_warnings(d);
}

TEST(GltfImporter, BlenderMaterialsMapToConductorAndPlastic) {
    SceneDesc d = import_gltf_file(blender_file("blender_scene.gltf"));
    ASSERT_EQ(d.materials.size(), 4u);
    ASSERT_EQ(d.shapes.size(), 4u);
    // Floor: dielectric, roughness 0.9 -> rough plastic with alpha 0.81 over the base colour.
    const auto& floor = std::get<PlasticBsdf>(d.materials.at("Floor").bsdf);
    EXPECT_NEAR(floor.alpha, 0.81, 1e-5);
    EXPECT_FLOAT_EQ(floor.eta, 1.5f);
    EXPECT_EQ(floor.distribution, MicrofacetType::GGX);
    expect_rgb_near(floor.diffuse_reflectance, 0.5, 0.5, 0.5);
    // Checker: base colour texture kept; the roughness texture (G = 0.2 | 0.8 stripes) averaged.
    const MaterialDesc& checker = d.materials.at("Checker");
    const auto& cp = std::get<PlasticBsdf>(checker.bsdf);
    EXPECT_NEAR(cp.alpha, 0.5 * 0.5, 1e-3);
    ASSERT_TRUE(checker.reflectance_texture.has_value());
    EXPECT_EQ(std::filesystem::path(checker.reflectance_texture->file).filename(), "checker.png");
    EXPECT_FALSE(checker.reflectance_texture->raw);  // glTF base colour textures are sRGB
    // Gold: metallic 1 -> conductor with Fresnel 1 tinted by the base colour, alpha = 0.3^2.
    const auto& gold = std::get<ConductorBsdf>(d.materials.at("Gold").bsdf);
    EXPECT_FALSE(gold.has_ior);
    expect_rgb_near(gold.specular_reflectance, 1.0, 0.71, 0.29);
    EXPECT_NEAR(gold.alpha_u, 0.09, 1e-5);
    EXPECT_NEAR(gold.alpha_v, 0.09, 1e-5);
    // The emissive panel: emissiveFactor x KHR_materials_emissive_strength 4, both sides.
    int emitters = 0;
    for (const ShapeDesc& sh : d.shapes) {
        EXPECT_EQ(sh.type, ShapeType::Mesh);
        EXPECT_EQ(sh.mesh_parts.size(), 1u);
        if (!sh.emitter) continue;
        ++emitters;
        EXPECT_EQ(sh.material, "Panel");
        expect_rgb_near(sh.emitter->radiance, 4, 3.2, 2.4);
        EXPECT_TRUE(sh.emitter->two_sided);
    }
    EXPECT_EQ(emitters, 1);
    // Each approximation warned once, naming the objects.
    for (const char* w : {"metals become a conductor", "dielectrics become Omega's plastic",
                          "metallicRoughness texture becomes its mean"}) {
        int n = 0;
        for (const auto& s : d.warnings) n += s.find(w) != std::string::npos;
        EXPECT_EQ(n, 1) << w << "\n" << all_warnings(d);
    }
    EXPECT_TRUE(has_warning(d, "'Floor'")) << all_warnings(d);
    EXPECT_TRUE(has_warning(d, "blender_scene.gltf: materials[2] 'Gold': metals")) << all_warnings(d);
}

// The shapes keep the geometry in the glTF file; the file's node transforms place it.
TEST(GltfImporter, NodeTransformsPlaceTheMeshes) {
    SceneDesc d = import_gltf_file(blender_file("blender_scene.gltf"));
    const ShapeDesc* sphere = nullptr;
    for (const ShapeDesc& sh : d.shapes)
        if (sh.material == "Gold") sphere = &sh;
    ASSERT_TRUE(sphere);
    MeshFileOptions mo;
    mo.parts = sphere->mesh_parts;
    TriangleMesh m = load_mesh_file(*FileGate::unconfined(), sphere->file, sphere->loc, mo);
    Vec3d lo{1e9, 1e9, 1e9}, hi{-1e9, -1e9, -1e9};
    for (const Vec3& p : m.positions) {
        lo = {std::min(lo.x, double(p.x)), std::min(lo.y, double(p.y)), std::min(lo.z, double(p.z))};
        hi = {std::max(hi.x, double(p.x)), std::max(hi.y, double(p.y)), std::max(hi.z, double(p.z))};
    }
    // Blender: radius 0.6 at (0.9, -0.2, 0.6) -> glTF (0.9, 0.6, 0.2).
    expect_vec({(lo.x + hi.x) / 2, (lo.y + hi.y) / 2, (lo.z + hi.z) / 2}, {0.9, 0.6, 0.2}, 1e-3);
    EXPECT_NEAR(hi.y - lo.y, 1.2, 1e-3);
    // And the whole scene builds, every shape loading its part of the file.
    auto scene = Scene::build(d);
    EXPECT_TRUE(scene);
}

// Written by omega import and parsed back, the description is the same (meshes: [...] included).
TEST(GltfImporter, WrittenYamlParsesBackToTheSameScene) {
    TempDir t;
    SceneDesc d = import_gltf_file(blender_file("blender_scene.gltf"));
    const std::string yaml = (t.path / "scene.yaml").string();
    write_scene_file(d, yaml);
    SceneDesc e = parse_scene_file(yaml);
    EXPECT_EQ(e.sensor.to_world.m, d.sensor.to_world.m);
    EXPECT_EQ(e.sensor.fov, d.sensor.fov);
    ASSERT_EQ(e.shapes.size(), d.shapes.size());
    for (size_t i = 0; i < d.shapes.size(); ++i) {
        EXPECT_EQ(e.shapes[i].mesh_parts, d.shapes[i].mesh_parts);
        EXPECT_EQ(e.shapes[i].file, d.shapes[i].file);
    }
    ASSERT_EQ(e.lights.size(), 3u);
    EXPECT_EQ(e.lights[0].intensity.x, d.lights[0].intensity.x);
}

TEST(GltfImporter, UnknownExtensionsWarnByName) {
    TempDir t;
    auto p = t.write("ext.gltf", tiny_gltf(R"(, "extensionsUsed": ["KHR_materials_clearcoat", "KHR_lights_punctual"],
        "extensionsRequired": ["EXT_weird"])"));
    SceneDesc d = import_gltf_file(p.string());
    EXPECT_TRUE(has_warning(d, "ext.gltf: extensionsUsed[0]: extension 'KHR_materials_clearcoat' is not supported"))
        << all_warnings(d);
    EXPECT_TRUE(has_warning(d, "extensionsRequired[0]: required extension 'EXT_weird'")) << all_warnings(d);
    EXPECT_FALSE(has_warning(d, "'KHR_lights_punctual'")) << all_warnings(d);
    EXPECT_TRUE(has_warning(d, "the file has no camera")) << all_warnings(d);
    ASSERT_EQ(d.shapes.size(), 1u);
    EXPECT_TRUE(d.shapes[0].emitter.has_value());
}

// A buffer uri that leaves the scene's folder is refused by a confined gate, naming the file and
// the key, exactly as mesh loading refuses an escaping file.
TEST(GltfImporter, EscapingBufferUriIsRefusedWithFileAndKey) {
    TempDir t;
    t.write("outside.bin", std::string(36, '\0'));
    auto p = t.write("job/scene.gltf", tiny_gltf("", "../outside.bin"));
    GltfOptions opt;
    opt.files = FileGate::confined({(t.path / "job").string()});
    std::string err = scene_error_of([&] { import_gltf_file(p.string(), opt); });
    EXPECT_NE(err.find("scene.gltf:1: buffers[0].uri:"), std::string::npos) << err;
    EXPECT_NE(err.find("outside.bin"), std::string::npos) << err;
    // Unconfined (omega render of one's own files), the same file reads.
    EXPECT_NO_THROW(import_gltf_file(p.string()));
}

TEST(GltfImporter, DispatchByExtension) {
    EXPECT_TRUE(is_gltf_path("a/b.GLTF"));
    EXPECT_TRUE(is_gltf_path("b.glb"));
    EXPECT_FALSE(is_gltf_path("b.gltf.yaml"));
    MitsubaOptions opt;
    opt.camera = "TopCamera";
    EXPECT_EQ(load_scene_file(blender_file("blender_scene.gltf"), opt).sensor.type, SensorType::Orthographic);
    TempDir t;
    auto y = t.write("s.yaml", "omega: 1\n");
    std::string err = scene_error_of([&] { load_scene_file(y.string(), opt); });
    EXPECT_NE(err.find("only glTF scenes name their cameras"), std::string::npos) << err;
}
