// Bitmap reflectance in scene format v1: parsing, errors, the writer's round trip, and what
// Scene::build loads (only referenced textures, each file once).
#include <gtest/gtest.h>

#include "scene/scene.h"
#include "scene/scene_parser.h"
#include "scene/scene_writer.h"
#include "scene/test_helpers.h"
#include "test_images.h"

using namespace omega;
using omega::test::scene_error_of;
using omega::test::TempDir;

namespace {

const char* kHead = "omega: 1\nlights: [{type: constant, radiance: 1}]\n";

struct Fixture {
    TempDir dir;
    Fixture() {
        test::write_image_u8((dir.path / "textures/wood.png").string(), 2, 1, 3, {255, 0, 0, 0, 0, 255});
        dir.write("textures/junk.png", "not an image");
    }
    SceneDesc parse(const std::string& body) const {
        return parse_scene_string(std::string(kHead) + body, (dir.path / "scene.yaml").string());
    }
    std::string error(const std::string& body) const {
        return scene_error_of([&] { parse(body); });
    }
};

TEST(TextureScene, BitmapReflectanceParses) {
    Fixture f;
    SceneDesc d = f.parse(R"(materials:
  wood: {type: diffuse, reflectance: {type: bitmap, file: textures/wood.png, filter: nearest, wrap: clamp, raw: true,
         to_uv: [{scale: [2, 3]}, {translate: [0.5, 0.25]}]}}
  plain: {type: diffuse, reflectance: [0.1, 0.2, 0.3]}
shapes:
  - {type: rectangle, material: wood}
  - {type: cube, material: plain}
  - {type: sphere, material: {type: diffuse, reflectance: {type: bitmap, file: textures/wood.png}}}
)");
    const auto& t = d.materials.at("wood").reflectance_texture;
    ASSERT_TRUE(t);
    EXPECT_EQ(t->file, (f.dir.path / "textures/wood.png").lexically_normal().string());
    EXPECT_EQ(t->filter, TexFilter::Nearest);
    EXPECT_EQ(t->wrap, TexWrap::Clamp);
    EXPECT_TRUE(t->raw);
    EXPECT_EQ(t->to_uv.m, (std::array<float, 6>{2, 0, 0.5f, 0, 3, 0.25f}));  // scale first, then translate
    EXPECT_EQ(t->loc.key, "materials.wood.reflectance");
    EXPECT_FALSE(d.materials.at("plain").reflectance_texture);
    const auto& inl = d.materials.at("shapes[2].material").reflectance_texture;
    ASSERT_TRUE(inl);
    EXPECT_EQ(inl->filter, TexFilter::Bilinear);  // Mitsuba's defaults
    EXPECT_EQ(inl->wrap, TexWrap::Repeat);
    EXPECT_FALSE(inl->raw);
    EXPECT_TRUE(inl->to_uv.is_identity());
}

TEST(TextureScene, ErrorsNameTheLineAndKey) {
    Fixture f;
    // Line numbers: kHead has 2 lines, so the material is on line 4.
    std::string e = f.error("materials:\n  m: {type: diffuse, reflectance: {type: bitmap, file: textures/nope.png}}\n");
    EXPECT_NE(e.find("scene.yaml:4: materials.m.reflectance.file: cannot open 'textures/nope.png'"), std::string::npos) << e;
    e = f.error("materials:\n  m: {type: diffuse, reflectance: {type: bitmap, file: textures/wood.png, filtre: nearest}}\n");
    EXPECT_NE(e.find("scene.yaml:4: materials.m.reflectance.filtre: unknown key"), std::string::npos) << e;
    e = f.error("materials:\n  m: {type: diffuse, reflectance: {type: bitmap, file: textures/wood.png, wrap: tile}}\n");
    EXPECT_NE(e.find("materials.m.reflectance.wrap: expected one of repeat, mirror, clamp"), std::string::npos) << e;
    e = f.error("materials:\n  m: {type: diffuse, reflectance: {type: checkerboard}}\n");
    EXPECT_NE(e.find("materials.m.reflectance.type: expected one of bitmap"), std::string::npos) << e;
    e = f.error("materials:\n  m: {type: diffuse, reflectance: {type: bitmap}}\n");
    EXPECT_NE(e.find("materials.m.reflectance.file: missing key"), std::string::npos) << e;
    e = f.error("materials:\n  m: {type: diffuse, reflectance: {type: bitmap, file: textures/wood.png, to_uv: {scale: [1, 2, 3]}}}\n");
    EXPECT_NE(e.find("materials.m.reflectance.to_uv.scale: expected a number or [u, v]"), std::string::npos) << e;
    e = f.error("materials:\n  m: {type: diffuse, reflectance: {type: bitmap, file: textures/wood.png, to_uv: {spin: 3}}}\n");
    EXPECT_NE(e.find("materials.m.reflectance.to_uv.spin: unknown key"), std::string::npos) << e;
    e = f.error("shapes:\n  - {type: cube, flip_tex_coords: false}\n");
    EXPECT_NE(e.find("flip_tex_coords: not used by this shape type (only mesh)"), std::string::npos) << e;
}

TEST(TextureScene, UndecodableFileIsASceneErrorAtBuild) {
    Fixture f;
    SceneDesc d = f.parse("materials:\n  m: {type: diffuse, reflectance: {type: bitmap, file: textures/junk.png}}\n"
                          "shapes:\n  - {type: rectangle, material: m}\n");
    std::string e = scene_error_of([&] { Scene::build(d); });
    EXPECT_NE(e.find("scene.yaml:4: materials.m.reflectance: cannot read texture 'textures/junk.png': "), std::string::npos)
        << e;
}

TEST(TextureScene, BuildLoadsOnlyReferencedTexturesAndEachFileOnce) {
    Fixture f;
    SceneDesc d = f.parse(R"(materials:
  unused: {type: diffuse, reflectance: {type: bitmap, file: textures/junk.png}}
  a: {type: diffuse, reflectance: {type: bitmap, file: textures/wood.png}}
  b: {type: diffuse, reflectance: {type: bitmap, file: textures/wood.png, filter: nearest}}
  c: {type: diffuse, reflectance: {type: bitmap, file: textures/wood.png, raw: true}}
shapes:
  - {type: rectangle, material: a}
  - {type: rectangle, material: b}
  - {type: rectangle, material: c}
)");
    auto scene = Scene::build(d);  // the junk texture of the unused material is never read
    auto tex = [&](size_t shape) {
        return std::get<DiffuseBsdf>(scene->materials()[scene->shapes()[shape].material]).reflectance_tex;
    };
    ASSERT_TRUE(tex(0) && tex(1) && tex(2));
    EXPECT_EQ(tex(0)->image.get(), tex(1)->image.get());  // one decode for both
    EXPECT_NE(tex(0)->image.get(), tex(2)->image.get());  // raw decodes differently
    EXPECT_EQ(tex(1)->filter, TexFilter::Nearest);
    // The stand-in reflectance is the texture's mean: red and blue, sRGB-decoded 1.
    Rgb mean = std::get<DiffuseBsdf>(scene->materials()[0]).reflectance;
    EXPECT_FLOAT_EQ(mean.x, 0.5f);
    EXPECT_FLOAT_EQ(mean.y, 0.f);
    EXPECT_FLOAT_EQ(mean.z, 0.5f);
}

// A plastic's diffuse_reflectance may be a bitmap too; resolve_bsdf looks it up per hit and
// leaves the coat's parameters (eta, fdr_int, roughness) alone.
TEST(TextureScene, PlasticDiffuseReflectanceIsTextured) {
    Fixture f;
    SceneDesc d = f.parse(R"(materials:
  p: {type: roughplastic, alpha: 0.2, int_ior: 1.5, ext_ior: 1, nonlinear: true,
      diffuse_reflectance: {type: bitmap, file: textures/wood.png, filter: nearest, raw: true}}
shapes:
  - {type: rectangle, material: p}
)");
    ASSERT_TRUE(d.materials.at("p").reflectance_texture);
    auto scene = Scene::build(d);
    const Bsdf& b = scene->materials()[scene->shapes()[0].material];
    const auto& p = std::get<PlasticBsdf>(b);
    ASSERT_TRUE(p.diffuse_reflectance_tex);
    EXPECT_TRUE(bsdf_is_textured(b));
    Bsdf tmp;
    // Texel 0 (u < 1/2) is red, texel 1 blue (raw 8-bit: 255 -> 1).
    const auto& left = std::get<PlasticBsdf>(resolve_bsdf(b, {0.25f, 0.5f}, tmp));
    EXPECT_EQ(left.diffuse_reflectance, (Rgb{1, 0, 0}));
    EXPECT_EQ(left.diffuse_reflectance_tex, nullptr);
    EXPECT_EQ(left.fdr_int, p.fdr_int);
    EXPECT_EQ(left.alpha, 0.2f);
    EXPECT_TRUE(left.nonlinear);
    const auto& right = std::get<PlasticBsdf>(resolve_bsdf(b, {0.75f, 0.5f}, tmp));
    EXPECT_EQ(right.diffuse_reflectance, (Rgb{0, 0, 1}));
    // The writer keeps the bitmap.
    SceneDesc back = parse_scene_string(write_scene_yaml(d, ""), (f.dir.path / "back.yaml").string());
    ASSERT_TRUE(back.materials.at("p").reflectance_texture);
    EXPECT_TRUE(std::holds_alternative<PlasticBsdf>(back.materials.at("p").bsdf));
}

TEST(TextureScene, WriterRoundTripsTextures) {
    Fixture f;
    SceneDesc d = f.parse(R"(materials:
  wood: {type: diffuse, reflectance: {type: bitmap, file: textures/wood.png, filter: nearest, wrap: mirror, raw: true,
         to_uv: [{rotate: 30}, {scale: 0.3}, {translate: [0.1, 0.7]}]}}
shapes:
  - {type: rectangle, material: wood}
)");
    for (const std::string& base : {std::string(), f.dir.path.string()}) {
        std::string yaml = write_scene_yaml(d, base);
        if (!base.empty()) {
            EXPECT_NE(yaml.find("file: \"textures/wood.png\""), std::string::npos) << yaml;
        }
        SceneDesc back = parse_scene_string(yaml, (f.dir.path / "back.yaml").string());
        const auto &a = *d.materials.at("wood").reflectance_texture, &b = *back.materials.at("wood").reflectance_texture;
        EXPECT_EQ(a.file, b.file);
        EXPECT_EQ(a.filter, b.filter);
        EXPECT_EQ(a.wrap, b.wrap);
        EXPECT_EQ(a.raw, b.raw);
        EXPECT_EQ(a.to_uv.m, b.to_uv.m) << yaml;  // bit for bit
        std::string again = write_scene_yaml(back, base);
        EXPECT_EQ(again.substr(again.find("omega: 1")), yaml.substr(yaml.find("omega: 1")));
    }
}

}  // namespace
