// The omega program is built apart from this test: scripts/build links the renderer into it with
// link-time optimisation (renderer/CMakeLists.txt, OMEGA_LTO), while the test programs take the
// renderer's plain machine code. Parts rendered by differently built programs must still merge
// exactly, and the tests must speak for what users run, so both builds must render the same
// bits. This renders real scenes with every integrator through `omega render` and through the
// library in this process, and compares every pixel's mean and variance exactly.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "film/film.h"
#include "run_omega.h"
#include "scene/mitsuba_importer.h"
#include "shared_data.h"
#include "render_harness.h"

namespace omega {
namespace {

namespace fs = std::filesystem;

IntegratorType integrator_of(const std::string& name) {
    return name == "light" ? IntegratorType::Light : name == "bdpt" ? IntegratorType::Bdpt : IntegratorType::Path;
}

// The number of float values (means and variances) that differ between the two images.
size_t differing_values(const ExrImage& a, const ExrImage& b) {
    size_t n = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) n += std::memcmp(&a.rgb[i], &b.rgb[i], sizeof(float)) != 0;
    for (size_t i = 0; i < a.var.size(); ++i) n += std::memcmp(&a.var[i], &b.var[i], sizeof(float)) != 0;
    return n;
}

class ProgramBuild : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("omega_program_build_" + std::to_string(::getpid()));
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    // `scene` rendered by `omega render` and by the library, `spp` samples, each integrator.
    void expect_same_bits(const std::string& scene, long long spp) {
        for (const char* integrator : {"path", "light", "bdpt"}) {
            SCOPED_TRACE(scene + ", " + integrator);
            const std::string out = (dir_ / "program.exr").string();
            const auto r = test::run_omega("render " + scene + " --integrator " + integrator + " --spp " +
                                           std::to_string(spp) + " --seed 5 --threads 2 -q -o " + out);
            ASSERT_EQ(r.code, 0) << r.output;
            const ExrImage program = read_exr(out);

            SceneDesc desc = load_scene_file(scene);
            desc.integrator.type = integrator_of(integrator);
            const test::RenderResult lib = test::render(desc, spp, 5, 1);
            const std::string mine = (dir_ / "library.exr").string();
            write_exr(mine, lib.film(), ExrMeta{});
            const ExrImage library = read_exr(mine);

            ASSERT_EQ(program.width, library.width);
            ASSERT_EQ(program.height, library.height);
            ASSERT_EQ(program.rgb.size(), library.rgb.size());
            ASSERT_EQ(program.var.size(), library.var.size());
            EXPECT_EQ(differing_values(program, library), 0u) << "of " << program.rgb.size() + program.var.size();
            bool lit = false;
            for (float v : program.rgb) lit = lit || v > 0;
            EXPECT_TRUE(lit) << "a black image proves nothing";
        }
    }
    fs::path dir_;
};

// The Cornell box (area light, vertex normals, diffuse), its film made small.
TEST_F(ProgramBuild, CornellBoxSameBitsAsTheLibrary) {
    std::ifstream in(test::source_dir() + "/scenes/cornell-box.yaml");
    std::stringstream text;
    text << in.rdbuf();
    const std::string small =
        std::regex_replace(text.str(), std::regex(R"(film: \{width: \d+, height: \d+)"), "film: {width: 40, height: 40");
    ASSERT_NE(small, text.str()) << "the scene's film line changed";
    const std::string scene = (dir_ / "cornell.yaml").string();
    std::ofstream(scene) << small;
    expect_same_bits(scene, 4);
}

// Textures through the image module, rough conductors and an environment map: the code the
// example scenes never reach.
TEST_F(ProgramBuild, MaterialScenesSameBitsAsTheLibrary) {
    for (const char* name : {"textured-conductor", "envmap", "plastic-spheres"}) {
        const std::string scene = test::shared_path(std::string("scenes/materials/") + name + "/scene.xml");
        if (!test::shared_available(scene)) GTEST_SKIP() << scene;
        expect_same_bits(scene, 1);
    }
}

}  // namespace
}  // namespace omega
