// `omega render scene.gltf` and `omega import scene.gltf` on Blender's export (tests/data/gltf).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "film/film.h"
#include "run_omega.h"

namespace fs = std::filesystem;

namespace {

using Result = omega::test::OmegaResult;
using omega::test::run_omega;

std::string data(const std::string& name) {
    return (fs::path(OMEGA_SOURCE_DIR) / "tests/data/gltf" / name).string();
}

class GltfCli : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               fs::path("omega_gltf_cli_" + std::to_string(::getpid()) + "_" +
                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    fs::path dir_;
};

}  // namespace

TEST_F(GltfCli, RendersBlenderExportAndImportedYamlRendersTheSameImage) {
    Result a = run_omega("render " + data("blender_scene.gltf") + " -q --spp 2 --threads 2 -o " + path("a.exr"));
    ASSERT_EQ(a.code, 0) << a.output;
    // The approximations are warned, naming the file.
    EXPECT_NE(a.output.find("blender_scene.gltf: "), std::string::npos) << a.output;
    omega::ExrImage ia = omega::read_exr(path("a.exr"));
    EXPECT_EQ(ia.width, 320);
    EXPECT_EQ(ia.height, 240);
    EXPECT_EQ(ia.attributes["omega.nonfinite"], "0");
    double sum = 0;
    for (float v : ia.rgb) {
        ASSERT_TRUE(std::isfinite(v));
        sum += v;
    }
    EXPECT_GT(sum / double(ia.rgb.size()), 0.01);  // lit, not black

    // The YAML beside the glTF (so that its mesh paths are short); it renders the same image.
    const std::string yaml = path("scene.yaml");
    Result imp = run_omega("import " + data("blender_scene.gltf") + " -o " + yaml);
    ASSERT_EQ(imp.code, 0) << imp.output;
    EXPECT_NE(imp.output.find("4 shapes, 4 materials, 3 lights"), std::string::npos) << imp.output;
    Result b = run_omega("render " + yaml + " -q --spp 2 --threads 2 -o " + path("b.exr"));
    ASSERT_EQ(b.code, 0) << b.output;
    omega::ExrImage ib = omega::read_exr(path("b.exr"));
    EXPECT_EQ(ia.rgb, ib.rgb);
}

TEST_F(GltfCli, CameraFlagPicksTheOrthographicCamera) {
    Result r = run_omega("render " + data("blender_scene.gltf") + " -q --spp 1 --camera TopCamera -o " + path("top.exr"));
    ASSERT_EQ(r.code, 0) << r.output;
    Result bad = run_omega("render " + data("blender_scene.gltf") + " -q --spp 1 --camera Nope -o " + path("x.exr"));
    EXPECT_EQ(bad.code, 2) << bad.output;
    EXPECT_NE(bad.output.find("--camera Nope: no such camera"), std::string::npos) << bad.output;
}

// Blender's .glb embeds its images: it renders the same image as its .gltf with the files beside
// it (same seed, same spp), says nothing about embedded images, and `omega import` writes the
// base colour image into <yaml stem>_textures/, from where the YAML renders the same image again.
TEST_F(GltfCli, GlbWithEmbeddedImagesRendersLikeItsGltf) {
    Result a = run_omega("render " + data("blender_scene.gltf") + " -q --spp 1 --threads 2 --seed 3 -o " + path("a.exr"));
    ASSERT_EQ(a.code, 0) << a.output;
    Result b = run_omega("render " + data("blender_scene.glb") + " -q --spp 1 --threads 2 --seed 3 -o " + path("b.exr"));
    ASSERT_EQ(b.code, 0) << b.output;
    EXPECT_EQ(b.output.find("embedded"), std::string::npos) << b.output;
    omega::ExrImage ia = omega::read_exr(path("a.exr")), ib = omega::read_exr(path("b.exr"));
    EXPECT_EQ(ia.rgb, ib.rgb);

    Result imp = run_omega("import " + data("blender_scene.glb") + " -o " + path("out.yaml"));
    ASSERT_EQ(imp.code, 0) << imp.output;
    EXPECT_TRUE(fs::exists(path("out_textures/checker.png")));
    Result c = run_omega("render " + path("out.yaml") + " -q --spp 1 --threads 2 --seed 3 -o " + path("c.exr"));
    ASSERT_EQ(c.code, 0) << c.output;
    EXPECT_EQ(omega::read_exr(path("c.exr")).rgb, ia.rgb);
}
