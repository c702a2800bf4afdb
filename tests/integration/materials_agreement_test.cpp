// Path tracing, light tracing and BDPT agree (block z-tests, as IntegratorAgreement does) on the
// Cornell box with the surface features of issue 11 that change where and how paths scatter:
// a fractional mask (the hash coin of Scene's filter decides pass-through for camera rays, walks,
// shadow rays and connections alike), a bump-mapped wall (tilted shading normals: the light
// subpaths' adjoint correction) and a thin dielectric sheet (delta reflection and transmission).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "render_harness.h"
#include "scene/scene_parser.h"
#include "test_images.h"

namespace omega {
namespace {

namespace fs = std::filesystem;

SceneDesc cornell() {
    SceneDesc d = parse_scene_file(OMEGA_SOURCE_DIR "/scenes/cornell-box.yaml");
    d.sensor.film.width = d.sensor.film.height = 24;
    d.sensor.film.filter = FilterType::Box;
    d.sensor.film.filter_radius = 0.5f;
    d.integrator.max_depth = 5;
    return d;
}

// z-test of integrator a against b over 4 x 4 blocks and the whole image, `family` comparisons.
void expect_same(const SceneDesc& base, IntegratorType a, IntegratorType b, long long spp_a, long long spp_b,
                 int family, const char* what) {
    SceneDesc da = base, db = base;
    da.integrator.type = a;
    db.integrator.type = b;
    auto ra = test::render(da, spp_a, 303);
    auto rb = test::render(db, spp_b, 404);
    for (const auto* r : {&ra, &rb}) {
        EXPECT_EQ(r->report.nonfinite, 0u) << what;
        EXPECT_EQ(r->report.mis_errors, 0u) << what;
    }
    auto z = test::z_between(ra.film(), rb.film(), 4);
    std::printf("[agreement] %s: image z %+.2f, worst block |z| %.2f of %d blocks\n", what, z.z, z.max_abs_z, z.blocks);
    EXPECT_LT(z.max_abs_z, test::z_threshold(z.blocks * family)) << what << ": worst block z";
    EXPECT_LT(std::abs(z.z), test::z_threshold(family)) << what << ": image z";
}

// Both boxes half there (opacity 0.5: a coin per ray), the back wall bump mapped by an egg-crate
// height field (tilts up to ~14 degrees).
TEST(MaterialsAgreement, MaskedBoxesBumpedWall) {
    const fs::path png = fs::temp_directory_path() / ("omega_bump_" + std::to_string(::getpid()) + ".png");
    std::vector<uint8_t> h;
    const int n = 64;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            h.push_back(uint8_t(std::lround(127.5 + 100.0 * std::sin(2 * kPiD * 4 * (x + 0.5) / n) *
                                                        std::sin(2 * kPiD * 4 * (y + 0.5) / n))));
    test::write_image_u8(png.string(), n, n, 1, h);
    SceneDesc d = cornell();
    MaterialDesc half{"half", DiffuseBsdf{{0.7f, 0.6f, 0.3f}, true}, {}};
    half.opacity = 0.5f;
    d.materials["half"] = half;
    MaterialDesc& wall = d.materials.at("BackWallBSDF");
    wall.bump_texture = BitmapDesc{};
    wall.bump_texture->file = png.string();
    wall.bump_texture->raw = true;
    wall.bump_scale = 0.05f;  // |dp/du| = 2, max slope 0.39 x 8 pi: tan(tilt) up to 0.25
    for (auto& s : d.shapes)
        if (s.type == ShapeType::Cube) s.material = "half";
    const IntegratorType P = IntegratorType::Path, L = IntegratorType::Light, B = IntegratorType::Bdpt;
    expect_same(d, P, B, 256, 128, 3, "mask+bump path-bdpt");
    expect_same(d, L, B, 256, 128, 3, "mask+bump light-bdpt");
    expect_same(d, P, L, 256, 256, 3, "mask+bump path-light");
    fs::remove(png);
}

// Textured roughness, reflectance and transmittance (resolve_textured per hit, in the walks and
// in every connection's densities): the boxes as a rough conductor with a checkered alpha and
// tint, and a rough glass with a checkered alpha and transmittance; the back wall a rough
// plastic with a checkered alpha. All three lobes are glossy, so every integrator reaches them.
TEST(MaterialsAgreement, TexturedRoughnessAndTransmittance) {
    SceneDesc d = cornell();
    auto checker = [](Rgb c0, Rgb c1, float scale) {
        BitmapDesc t;
        t.checker = true;
        t.color0 = c0;
        t.color1 = c1;
        t.to_uv.m = {scale, 0, 0, 0, scale, 0};
        return t;
    };
    MaterialDesc metal{"metal", ConductorBsdf{}, {}};
    metal.alpha_texture = checker(Rgb(0.05f), Rgb(0.4f), 2);
    metal.specular_texture = checker({0.9f, 0.7f, 0.3f}, Rgb(0.6f), 3);
    MaterialDesc glass{"glass", DielectricBsdf{}, {}};
    glass.alpha_texture = checker(Rgb(0.1f), Rgb(0.5f), 2);
    glass.transmittance_texture = checker({0.6f, 0.9f, 1.f}, Rgb(1.f), 2);
    d.materials["metal"] = metal;
    d.materials["glass"] = glass;
    PlasticBsdf coat;
    coat.alpha = 0.1f;
    coat.diffuse_reflectance = Rgb(0.6f);
    MaterialDesc& wall = d.materials.at("BackWallBSDF");
    wall.bsdf = coat;
    wall.reflectance_texture.reset();
    wall.alpha_texture = checker(Rgb(0.05f), Rgb(0.3f), 4);
    bool first = true;
    for (auto& s : d.shapes)
        if (s.type == ShapeType::Cube) {
            s.material = first ? "metal" : "glass";
            first = false;
        }
    const IntegratorType P = IntegratorType::Path, L = IntegratorType::Light, B = IntegratorType::Bdpt;
    expect_same(d, P, B, 256, 128, 2, "textured roughness path-bdpt");
    expect_same(d, L, B, 256, 128, 2, "textured roughness light-bdpt");
}

// The tall box as a thin sheet (windows on every face): the camera sees it directly, and E S ...
// paths are beyond a light tracer, so path tracing and bdpt only (bdpt's light subpaths cross the
// sheet in importance mode, and its delta vertices must drop out of the connections and MIS).
TEST(MaterialsAgreement, ThinSheetBox) {
    SceneDesc d = cornell();
    d.materials["sheet"] = MaterialDesc{"sheet", ThinDielectricBsdf{1.5f, {1, 1, 1}, {0.9f, 0.95f, 1.f}}, {}};
    for (auto& s : d.shapes)
        if (s.type == ShapeType::Cube) s.material = "sheet";
    expect_same(d, IntegratorType::Path, IntegratorType::Bdpt, 512, 256, 1, "thin sheet path-bdpt");
}

}  // namespace
}  // namespace omega
