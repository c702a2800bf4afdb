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
    e = f.error("materials:\n  m: {type: diffuse, reflectance: {type: noise}}\n");
    EXPECT_NE(e.find("materials.m.reflectance.type: expected one of bitmap, checkerboard"), std::string::npos) << e;
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

// Checkerboard on every textured parameter (diffuse, plastic, conductor specular_reflectance);
// the conductor's is new with it. No file is read for a checkerboard.
TEST(TextureScene, CheckerboardOnDiffusePlasticAndConductor) {
    Fixture f;
    SceneDesc d = f.parse(R"(materials:
  wall: {type: diffuse, reflectance: {type: checkerboard, color0: 0.8, color1: [0.1, 0.1, 0.15], to_uv: {scale: 4}}}
  p: {type: plastic, diffuse_reflectance: {type: checkerboard}}
  metal: {type: conductor, alpha: 0.1, specular_reflectance: {type: checkerboard, color0: 1, color1: 0.25,
          to_uv: {scale: [8, 4]}}}
  pane: {type: thindielectric, int_ior: 1.5, ext_ior: 1, specular_transmittance: [0.9, 0.9, 0.8]}
shapes:
  - {type: rectangle, material: wall}
  - {type: rectangle, material: p}
  - {type: sphere, material: metal}
  - {type: rectangle, material: pane}
)");
    const auto& t = *d.materials.at("wall").reflectance_texture;
    EXPECT_TRUE(t.checker);
    EXPECT_EQ(t.color0, Rgb(0.8f));
    EXPECT_EQ(t.to_uv.m, (std::array<float, 6>{4, 0, 0, 0, 4, 0}));
    ASSERT_TRUE(d.materials.at("metal").specular_texture);
    auto scene = Scene::build(d);
    Bsdf tmp;
    const Bsdf& wall = scene->materials()[scene->shapes()[0].material];
    EXPECT_EQ(std::get<DiffuseBsdf>(resolve_bsdf(wall, {0.01f, 0.01f}, tmp)).reflectance, Rgb(0.8f));
    EXPECT_EQ(std::get<DiffuseBsdf>(resolve_bsdf(wall, {0.2f, 0.01f}, tmp)).reflectance, (Rgb{0.1f, 0.1f, 0.15f}));
    const Bsdf& p = scene->materials()[scene->shapes()[1].material];
    EXPECT_EQ(std::get<PlasticBsdf>(resolve_bsdf(p, {0.1f, 0.1f}, tmp)).diffuse_reflectance, Rgb(0.4f));
    const Bsdf& metal = scene->materials()[scene->shapes()[2].material];
    EXPECT_TRUE(bsdf_is_textured(metal));
    EXPECT_EQ(std::get<ConductorBsdf>(metal).specular_reflectance, Rgb(0.625f));  // the mean
    EXPECT_EQ(scene->shapes()[2].uv_map, UvMap::Sphere);
    const auto& c = std::get<ConductorBsdf>(resolve_bsdf(metal, {0.01f, 0.01f}, tmp));
    EXPECT_EQ(c.specular_reflectance, Rgb(1.f));
    EXPECT_EQ(c.alpha_u, 0.1f);
    EXPECT_EQ(std::get<ConductorBsdf>(resolve_bsdf(metal, {0.1f, 0.01f}, tmp)).specular_reflectance, Rgb(0.25f));
    EXPECT_EQ(std::get<ThinDielectricBsdf>(scene->materials()[scene->shapes()[3].material]).specular_transmittance,
              (Rgb{0.9f, 0.9f, 0.8f}));
    // The writer keeps every texture and the sheet.
    std::string yaml = write_scene_yaml(d, "");
    SceneDesc back = parse_scene_string(yaml, (f.dir.path / "back.yaml").string());
    EXPECT_EQ(back.materials.at("wall").reflectance_texture->to_uv.m, t.to_uv.m) << yaml;
    EXPECT_EQ(back.materials.at("metal").specular_texture->color1, Rgb(0.25f)) << yaml;
    EXPECT_TRUE(std::holds_alternative<ThinDielectricBsdf>(back.materials.at("pane").bsdf)) << yaml;
    std::string again = write_scene_yaml(back, "");
    EXPECT_EQ(again.substr(again.find("omega: 1")), yaml.substr(yaml.find("omega: 1")));
    EXPECT_NE(f.error("materials: {m: {type: diffuse, reflectance: {type: checkerboard, file: x.png}}}\nshapes: []\n")
                  .find("file"),
              std::string::npos);
}

// Reflectance, transmittance and roughness take textures on every model that has them: each is
// looked up per hit (a roughness as the texel's luminance, clamped so that a textured microfacet
// lobe never turns into a delta), and the writer keeps them.
TEST(TextureScene, DielectricPlasticAndRoughnessTextures) {
    Fixture f;
    SceneDesc d = f.parse(R"(materials:
  glass: {type: dielectric, alpha: {type: checkerboard, color0: 0.3, color1: 0},
          specular_reflectance: {type: checkerboard, color0: 1, color1: 0.5},
          specular_transmittance: {type: checkerboard, color0: [0.2, 0.4, 0.6], color1: 1}}
  pane: {type: thindielectric, specular_reflectance: {type: checkerboard, color0: 0.9, color1: 0.1},
         specular_transmittance: {type: bitmap, file: textures/wood.png, filter: nearest}}
  coat: {type: roughplastic, alpha: {type: checkerboard, color0: [1, 0, 0], color1: 1},
         specular_reflectance: {type: checkerboard, color0: 0.25, color1: 1}}
  metal: {type: conductor, alpha: {type: checkerboard, color0: 0.05, color1: 0.5}}
  rough: {type: roughdiffuse, alpha: {type: checkerboard, color0: 0, color1: 0.9}}
shapes:
  - {type: rectangle, material: glass}
  - {type: rectangle, material: pane}
  - {type: rectangle, material: coat}
  - {type: rectangle, material: metal}
  - {type: rectangle, material: rough}
)");
    for (const char* m : {"glass", "coat", "metal", "rough"}) EXPECT_TRUE(d.materials.at(m).alpha_texture) << m;
    auto scene = Scene::build(d);
    auto bsdf = [&](int i) -> const Bsdf& { return scene->materials()[scene->shapes()[size_t(i)].material]; };
    const Vec2 c0{0.1f, 0.1f}, c1{0.7f, 0.1f};  // a check of color0, one of color1
    Bsdf tmp;
    for (int i = 0; i < 5; ++i) EXPECT_TRUE(bsdf_is_textured(bsdf(i))) << i;

    auto glass0 = std::get<DielectricBsdf>(resolve_bsdf(bsdf(0), c0, tmp));
    EXPECT_FLOAT_EQ(glass0.alpha_u, 0.3f);
    EXPECT_EQ(glass0.alpha_v, glass0.alpha_u);
    EXPECT_EQ(glass0.specular_reflectance, Rgb(1.f));
    EXPECT_EQ(glass0.specular_transmittance, (Rgb{0.2f, 0.4f, 0.6f}));
    EXPECT_FALSE(bsdf_is_textured(Bsdf(glass0)));
    auto glass1 = std::get<DielectricBsdf>(resolve_bsdf(bsdf(0), c1, tmp));
    EXPECT_EQ(glass1.alpha_u, kMinTexturedAlpha);  // a texel of 0 stays a (very sharp) glossy lobe
    EXPECT_EQ(glass1.specular_reflectance, Rgb(0.5f));
    EXPECT_EQ(glass1.specular_transmittance, Rgb(1.f));
    EXPECT_EQ(bsdf_lobes(bsdf(0)) & kLobeDelta, 0);  // classified by its mean roughness: glossy

    auto pane = std::get<ThinDielectricBsdf>(resolve_bsdf(bsdf(1), c1, tmp));
    EXPECT_EQ(pane.specular_reflectance, Rgb(0.1f));
    EXPECT_EQ(pane.specular_transmittance, (Rgb{0.f, 0.f, 1.f})) << "wood.png's right texel (blue)";

    auto coat0 = std::get<PlasticBsdf>(resolve_bsdf(bsdf(2), c0, tmp));
    EXPECT_NEAR(coat0.alpha, 0.212671f, 1e-6f);  // the luminance of red
    EXPECT_EQ(coat0.specular_reflectance, Rgb(0.25f));
    EXPECT_EQ(std::get<PlasticBsdf>(resolve_bsdf(bsdf(2), c1, tmp)).alpha, 1.f);

    EXPECT_FLOAT_EQ(std::get<ConductorBsdf>(resolve_bsdf(bsdf(3), c0, tmp)).alpha_u, 0.05f);
    EXPECT_FLOAT_EQ(std::get<ConductorBsdf>(resolve_bsdf(bsdf(3), c1, tmp)).alpha_v, 0.5f);
    EXPECT_FLOAT_EQ(std::get<ConductorBsdf>(bsdf(3)).alpha_u, 0.275f);  // the mean

    EXPECT_EQ(std::get<DiffuseBsdf>(resolve_bsdf(bsdf(4), c0, tmp)).alpha, 0.f);  // Lambert
    EXPECT_FLOAT_EQ(std::get<DiffuseBsdf>(resolve_bsdf(bsdf(4), c1, tmp)).alpha, 0.9f);

    // The writer keeps every texture where it was.
    std::string yaml = write_scene_yaml(d, "");
    SceneDesc back = parse_scene_string(yaml, (f.dir.path / "back.yaml").string());
    for (const auto& [name, m] : d.materials) {
        const auto a = m.texture_slots(), b = back.materials.at(name).texture_slots();
        for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i]->has_value(), b[i]->has_value()) << name << " slot " << i << yaml;
    }
    EXPECT_EQ(back.materials.at("pane").transmittance_texture->file, d.materials.at("pane").transmittance_texture->file);

    // Anisotropic roughness takes numbers; a smooth plastic has no alpha to texture.
    EXPECT_NE(f.error("materials: {m: {type: conductor, alpha_u: {type: checkerboard}, alpha_v: 0.1}}\nshapes: []\n")
                  .find("materials.m.alpha_u"),
              std::string::npos);
    EXPECT_NE(f.error("materials: {m: {type: plastic, alpha: {type: checkerboard}}}\nshapes: []\n").find("alpha"),
              std::string::npos);
}

// A masked quad in front of a floor: opacity 0 is not there for any query, opacity 1 is opaque,
// a bitmap's first channel decides per uv, and a fractional opacity lets through the fraction
// 1 - opacity of the rays (a hash coin, the same for the same ray).
TEST(TextureScene, MaskOpacityDropsHitsForEveryQuery) {
    Fixture f;
    auto scene_with = [&](const std::string& opacity) {
        SceneDesc d = f.parse("materials:\n  m: {type: diffuse, opacity: " + opacity + R"(}
shapes:
  - {type: rectangle, material: m, to_world: [{translate: [0, 0, 1]}]}
  - {type: rectangle, material: {type: diffuse}, to_world: [{scale: 4}]}
)");
        return Scene::build(d);
    };
    auto hits_mask = [](const Scene& s, Vec3 o) {
        SurfaceHit h;
        Ray r{o, Vec3(0, 0, -1)};
        bool hit = s.intersect(r, h);
        EXPECT_TRUE(hit);
        Ray shadow{o, Vec3(0, 0, -1), o.z - 0.5f};  // ends before the floor (z = 0), beyond the mask (z = 1)
        EXPECT_EQ(s.occluded(shadow), h.shape == 0);  // any-hit agrees with closest-hit
        return h.shape == 0;
    };
    auto none = scene_with("0");
    auto full = scene_with("1");
    EXPECT_FALSE(hits_mask(*none, {0.2f, 0.3f, 3}));
    EXPECT_TRUE(hits_mask(*full, {0.2f, 0.3f, 3}));
    EXPECT_FALSE(full->shapes()[0].masked());
    // wood.png: texel 0 (u < 1/2) red (first channel 1: opaque), texel 1 blue (0: a hole).
    auto bitmap = scene_with("{type: bitmap, file: textures/wood.png, filter: nearest, raw: true}");
    EXPECT_TRUE(hits_mask(*bitmap, {-0.5f, 0.f, 3}));  // rectangle uv u = (x + 1) / 2
    EXPECT_FALSE(hits_mask(*bitmap, {0.5f, 0.f, 3}));
    auto third = scene_with("0.3");
    int hit = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) hit += hits_mask(*third, {-0.9f + 1.8f * float(i % 200) / 200.f, -0.9f + 1.8f * float(i / 200) / 100.f, 3});
    EXPECT_NEAR(hit, 0.3 * n, 5 * std::sqrt(n * 0.3 * 0.7));
    EXPECT_EQ(hits_mask(*third, {0.1f, 0.1f, 3}), hits_mask(*third, {0.1f, 0.1f, 3}));  // deterministic
    EXPECT_NE(f.error("materials: {m: {type: diffuse, opacity: 1.5}}\nshapes: []\n"), "");
    EXPECT_NE(scene_error_of([&] {
                  Scene::build(f.parse("materials: {m: {type: diffuse, opacity: 0.5}}\nshapes: [{type: sphere, material: m}]\n"));
              }).find("sphere"),
              std::string::npos);
    EXPECT_NE(scene_error_of([&] {
                  Scene::build(f.parse("materials: {m: {type: diffuse, opacity: 0.5}}\nshapes: [{type: rectangle, material: m, "
                                       "emitter: {type: area, radiance: 1}}]\n"));
              }).find("emitting shape"),
              std::string::npos);
}

// Mitsuba's bumpmap on a rectangle: a height ramp in u tilts the shading normal by the analytic
// amount, dp/du' = dp/du + n g_u with dp/du = (2, 0, 0) for the unit rectangle.
TEST(TextureScene, BumpMapTiltsTheShadingNormal) {
    Fixture f;
    test::write_image_u8((f.dir.path / "ramp.png").string(), 4, 1, 1, {0, 64, 128, 192});
    SceneDesc d = f.parse(R"(materials:
  m: {type: diffuse, bump: {type: bitmap, file: ramp.png, raw: true}, bump_scale: 0.5}
shapes:
  - {type: rectangle, material: m}
)");
    ASSERT_TRUE(d.materials.at("m").bump_texture);
    auto scene = Scene::build(d);
    SurfaceHit h;
    ASSERT_TRUE(scene->intersect(Ray{{0.01f, 0.2f, 2.f}, {0, 0, -1}}, h));  // u = 0.505: between texels 1 and 2
    const float g = 0.5f * (64.f / 255.f) * 4.f;
    Vec3 expect = normalize(Vec3(-2.f * g, 0.f, 4.f));  // cross((2, 0, g), (0, 2, 0))
    EXPECT_NEAR(h.ns.x, expect.x, 1e-5f);
    EXPECT_NEAR(h.ns.y, expect.y, 1e-5f);
    EXPECT_NEAR(h.ns.z, expect.z, 1e-5f);
    EXPECT_EQ(h.ng, Vec3(0, 0, 1));  // the geometry is untouched
    // The writer keeps it.
    std::string yaml = write_scene_yaml(d, "");
    SceneDesc back = parse_scene_string(yaml, (f.dir.path / "back.yaml").string());
    ASSERT_TRUE(back.materials.at("m").bump_texture) << yaml;
    EXPECT_EQ(back.materials.at("m").bump_scale, 0.5f);
    EXPECT_NE(f.error("materials: {m: {type: diffuse, bump_scale: 2}}\nshapes: []\n").find("bump"), std::string::npos);
}

// The YAML envmap light: parsed with its file resolved against the scene's folder, scale and
// to_world; errors name the line and key; the image is read at build (a bad one is a SceneError
// there), and a scene holds one environment at most.
TEST(TextureScene, EnvmapLight) {
    TempDir dir;
    test::write_image_f32((dir.path / "sky/sky.exr").string(), 4, 2, 3, std::vector<float>(24, 0.25f));
    dir.write("sky/junk.exr", "not an image");
    auto parse = [&](const std::string& lights) {
        return parse_scene_string("omega: 1\nshapes:\n  - {type: sphere}\nlights:\n" + lights,
                                  (dir.path / "scene.yaml").string());
    };
    SceneDesc d = parse("  - {type: envmap, file: sky/sky.exr, scale: 2, to_world: {rotate: {axis: [0, 1, 0], angle: 90}}}\n");
    ASSERT_EQ(d.lights.size(), 1u);
    EXPECT_EQ(d.lights[0].type, LightType::EnvMap);
    EXPECT_EQ(d.lights[0].file, (dir.path / "sky/sky.exr").lexically_normal().string());
    EXPECT_EQ(d.lights[0].scale, 2.f);
    auto scene = Scene::build(d);
    ASSERT_EQ(scene->environment_light(), 0);
    EXPECT_NEAR(environment_le(scene->lights()[0], Vec3{0, 0, 1}).y, 0.5f, 1e-6f);
    std::string e = scene_error_of([&] { parse("  - {type: envmap, file: sky/none.exr}\n"); });
    EXPECT_NE(e.find("scene.yaml:5: lights[0].file: cannot open 'sky/none.exr'"), std::string::npos) << e;
    e = scene_error_of([&] { parse("  - {type: envmap, file: sky/sky.exr, scale: -1}\n"); });
    EXPECT_NE(e.find("lights[0].scale: must be >= 0"), std::string::npos) << e;
    e = scene_error_of([&] { parse("  - {type: envmap}\n"); });
    EXPECT_NE(e.find("lights[0].file: missing key"), std::string::npos) << e;
    e = scene_error_of([&] { Scene::build(parse("  - {type: envmap, file: sky/junk.exr}\n")); });
    EXPECT_NE(e.find("cannot read envmap 'sky/junk.exr'"), std::string::npos) << e;
    e = scene_error_of(
        [&] { Scene::build(parse("  - {type: constant, radiance: 1}\n  - {type: envmap, file: sky/sky.exr}\n")); });
    EXPECT_NE(e.find("only one environment"), std::string::npos) << e;
    // A black map (scale 0) emits nothing and is left out, as a black constant is.
    EXPECT_EQ(Scene::build(parse("  - {type: envmap, file: sky/sky.exr, scale: 0}\n"))->environment_light(), -1);
}

}  // namespace
