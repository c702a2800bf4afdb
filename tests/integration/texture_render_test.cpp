// Textured reflectance end to end. A textured plane under a constant environment, direct light
// only: the outgoing radiance is exactly albedo(uv) * Le (the plane sees its whole hemisphere),
// so every pixel of an orthographic view has a closed-form value. Then path, light and BDPT
// must agree on a Cornell box whose walls, boxes and a sphere are textured.
#include <gtest/gtest.h>

#include <cmath>

#include "render_harness.h"
#include "scene/scene_parser.h"
#include "scene/test_helpers.h"
#include "test_images.h"

namespace omega {
namespace {

// A 4 x 4 sRGB texture whose every texel differs, and whose rows differ (so a flipped v shows).
constexpr int kTex = 4, kRes = 8;
int code(int tx, int ty, int ch) {
    return ch == 0 ? 20 + 60 * ty + 13 * tx : ch == 1 ? 200 - 40 * ty : 30 + 50 * tx;
}

std::string write_texture(const test::TempDir& dir) {
    std::vector<uint8_t> px;
    for (int ty = 0; ty < kTex; ++ty)
        for (int tx = 0; tx < kTex; ++tx)
            for (int ch = 0; ch < 3; ++ch) px.push_back(uint8_t(code(tx, ty, ch)));
    std::string path = (dir.path / "albedo.png").string();
    test::write_image_u8(path, kTex, kTex, 3, px);
    return path;
}

constexpr float kLe = 1.5f;

SceneDesc plane_scene(const std::string& png) {
    SceneDesc d = test::empty_scene(kRes, kRes);
    d.integrator.max_depth = 2;
    d.sensor.type = SensorType::Orthographic;
    // Looking down at the rectangle [-1, 1]^2 with +y up: image right is +x, image down is -y.
    d.sensor.to_world = Mat4::look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0});
    MaterialDesc m = test::diffuse("tex", Rgb(0.5f));
    m.reflectance_texture = BitmapDesc{png, TexFilter::Nearest, TexWrap::Clamp};
    d.materials["tex"] = m;
    ShapeDesc plane;
    plane.type = ShapeType::Rectangle;
    plane.material = "tex";
    d.shapes.push_back(plane);
    LightDesc env;
    env.type = LightType::Constant;
    env.radiance = Rgb(kLe);
    d.lights.push_back(env);
    return d;
}

// Pixel (x, y) covers u in [x/8, (x+1)/8], v = (y+1)/2 with y the world coordinate, so
// v in [1 - (y+1)/8, 1 - y/8]: inside texel (x / 2, 3 - y / 2) in Mitsuba's v-down convention.
double expected(int x, int y, bool flip_v, double scale) {
    int tx = x / 2, ty = flip_v ? y / 2 : kTex - 1 - y / 2;
    double sum = 0;
    for (int ch = 0; ch < 3; ++ch) sum += test::srgb8_to_linear(code(tx, ty, ch));
    return scale * kLe * sum / 3.0;
}

TEST(TextureRender, TexturedPlaneMatchesAlbedoTimesRadiance) {
    test::TempDir dir;
    SceneDesc d = plane_scene(write_texture(dir));
    for (IntegratorType it : {IntegratorType::Path, IntegratorType::Bdpt}) {
        d.integrator.type = it;
        auto r = test::render(d, 64, 11);
        auto z = test::z_against(r.film(), [](int x, int y) { return expected(x, y, false, 1.0); });
        EXPECT_LT(std::abs(z.z), test::z_threshold(2)) << integrator_name(it) << " image z " << z.z;
        EXPECT_LT(z.max_abs_z, test::z_threshold(2 * kRes * kRes)) << integrator_name(it) << " worst pixel z";
        EXPECT_EQ(r.report.nonfinite, 0u);
        RecordProperty(std::string(integrator_name(it)) + "_z", std::to_string(z.z));
        RecordProperty(std::string(integrator_name(it)) + "_max_z", std::to_string(z.max_abs_z));
    }
}

// The sanity twin: the same render must fail the same test against a flipped v or a texture 10%
// too bright, so the test above can tell the convention and the values apart.
TEST(TextureRender, DetectsAFlippedVOrAWrongAlbedo) {
    test::TempDir dir;
    auto r = test::render(plane_scene(write_texture(dir)), 64, 12);
    auto flipped = test::z_against(r.film(), [](int x, int y) { return expected(x, y, true, 1.0); });
    EXPECT_GT(flipped.max_abs_z, test::z_threshold(kRes * kRes)) << "a flipped v went unnoticed";
    auto bright = test::z_against(r.film(), [](int x, int y) { return expected(x, y, false, 1.1); });
    EXPECT_GT(std::abs(bright.z), test::z_threshold(1)) << "a 10% error went unnoticed";
    RecordProperty("flipped_max_z", std::to_string(flipped.max_abs_z));
    RecordProperty("bright_z", std::to_string(bright.z));
}

// The Cornell box with textured floor, back wall (nearest, repeat x2), boxes (bilinear) and a
// textured sphere: light tracing and BDPT must see the same albedo as the path tracer at every
// vertex, including light-subpath vertices and connections.
TEST(TextureRender, PathLightAndBdptAgreeOnATexturedScene) {
    test::TempDir dir;
    std::string png = write_texture(dir);
    SceneDesc d = parse_scene_file(OMEGA_SOURCE_DIR "/scenes/cornell-box.yaml");
    d.sensor.film.width = d.sensor.film.height = 24;
    d.sensor.film.filter = FilterType::Box;
    d.sensor.film.filter_radius = 0.5f;
    d.integrator.max_depth = 4;
    for (const char* name : {"FloorBSDF", "BackWallBSDF"}) {
        auto& m = d.materials.at(name);
        m.reflectance_texture = BitmapDesc{png, TexFilter::Nearest, TexWrap::Repeat, false, UvTransform{{2, 0, 0, 0, 2, 0}}};
    }
    for (const char* name : {"ShortBoxBSDF", "TallBoxBSDF"}) d.materials.at(name).reflectance_texture = BitmapDesc{png};
    ShapeDesc ball;
    ball.type = ShapeType::Sphere;
    ball.center = {0.45, 0.85, 0.2};
    ball.radius = 0.18;
    ball.material = "ShortBoxBSDF";
    d.shapes.push_back(ball);

    const IntegratorType P = IntegratorType::Path, L = IntegratorType::Light, B = IntegratorType::Bdpt;
    struct Run { IntegratorType it; long long spp; uint64_t seed; };
    std::vector<test::RenderResult> r;
    for (Run run : {Run{P, 128, 301}, Run{L, 128, 302}, Run{B, 64, 303}}) {
        SceneDesc di = d;
        di.integrator.type = run.it;
        r.push_back(test::render(di, run.spp, run.seed));
        EXPECT_EQ(r.back().report.nonfinite, 0u) << integrator_name(run.it);
        EXPECT_EQ(r.back().report.mis_errors, 0u) << integrator_name(run.it);
    }
    const char* label[] = {"path-light", "path-bdpt", "light-bdpt"};
    const std::pair<int, int> pairs[] = {{0, 1}, {0, 2}, {1, 2}};
    for (int k = 0; k < 3; ++k) {
        auto z = test::z_between(r[size_t(pairs[k].first)].film(), r[size_t(pairs[k].second)].film(), 4);
        EXPECT_LT(z.max_abs_z, test::z_threshold(z.blocks * 3)) << label[k] << " worst block z";
        EXPECT_LT(std::abs(z.z), test::z_threshold(3)) << label[k] << " image z";
        RecordProperty(std::string(label[k]) + "_z", std::to_string(z.z));
        RecordProperty(std::string(label[k]) + "_max_block_z", std::to_string(z.max_abs_z));
    }
    // The sanity twin: the same comparison against an untextured render (the texture's mean
    // albedo everywhere) must fail, or agreement would prove nothing about the textures.
    SceneDesc flat = d;
    for (auto& [name, m] : flat.materials)
        if (m.reflectance_texture) {
            m.reflectance_texture.reset();
            std::get<DiffuseBsdf>(m.bsdf).reflectance = Rgb(0.35f);
        }
    flat.integrator.type = P;
    auto rf = test::render(flat, 128, 304);
    auto zf = test::z_between(rf.film(), r[2].film(), 4);
    EXPECT_GT(zf.max_abs_z, test::z_threshold(zf.blocks * 3)) << "an untextured render passed as textured";
}

}  // namespace
}  // namespace omega
