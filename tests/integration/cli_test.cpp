// `omega render` as a user runs it: exit codes, messages naming file:line: key, and the EXR.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "film/film.h"

namespace fs = std::filesystem;

namespace {

struct CmdResult {
    int code = -1;
    std::string output;  // stdout and stderr
};

CmdResult run(const std::string& args) {
    std::string cmd = std::string(OMEGA_BIN) + " " + args + " 2>&1";
    CmdResult r;
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
    int status = pclose(p);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

class CliTest : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / fs::path("omega_cli_" + std::to_string(::getpid()) + "_" +
                                                    ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string write(const std::string& name, const std::string& text) {
        fs::path p = dir_ / name;
        std::ofstream(p) << text;
        return p.string();
    }
    fs::path dir_;
};

const char* kGood = R"(omega: 1
integrator: {type: path, max_depth: 4}
sensor:
  type: perspective
  fov: 40
  to_world: {look_at: {origin: [0, 0, -3], target: [0, 0, 0], up: [0, 1, 0]}}
  film: {width: 16, height: 12}
  spp: 4
materials:
  white: {type: diffuse, reflectance: [0.5, 0.5, 0.5]}
shapes:
  - {type: sphere, center: [0, 0, 0], radius: 1, material: white}
lights:
  - {type: point, position: [0, 2, -2], intensity: [5, 5, 5]}
)";

TEST_F(CliTest, RendersAndWritesHeader) {
    std::string scene = write("good.yaml", kGood);
    std::string out = (dir_ / "out.exr").string();
    CmdResult r = run("render " + scene + " -o " + out + " --spp 3 --seed 9 --threads 2");
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("samples/s"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("rays/s"), std::string::npos) << r.output;
    omega::ExrImage img = omega::read_exr(out);
    EXPECT_EQ(img.width, 16);
    EXPECT_EQ(img.height, 12);
    EXPECT_EQ(img.var.size(), img.rgb.size());
    EXPECT_EQ(img.attributes["omega.spp"], "3");
    EXPECT_EQ(img.attributes["omega.integrator"], "path");
    EXPECT_EQ(img.attributes["omega.seed"], "9");
    EXPECT_EQ(img.attributes["omega.nonfinite"], "0");
    EXPECT_TRUE(img.attributes.count("omega.time_s"));
    EXPECT_TRUE(img.attributes.count("omega.warnings"));
}

TEST_F(CliTest, DefaultOutputIsTheSceneName) {
    std::string scene = write("named.yaml", kGood);
    std::string cmd = "cd " + dir_.string() + " && " + std::string(OMEGA_BIN) + " render named.yaml --spp 1 -q";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    EXPECT_TRUE(fs::exists(dir_ / "named.exr"));
}

struct BadCase {
    const char* name;
    std::string text;
    std::string expect;  // must appear in the message
};

TEST_F(CliTest, BadScenesExitWithCodeTwoAndNameTheProblem) {
    std::string good = kGood;
    auto replace = [&](const std::string& from, const std::string& to) {
        std::string s = good;
        s.replace(s.find(from), from.size(), to);
        return s;
    };
    write("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    std::vector<BadCase> cases = {
        {"malformed", replace("fov: 40", "fov: [40"), "bad.yaml:"},
        {"unknown_key", replace("fov: 40", "fvo: 40"), "fvo"},
        {"nested_unknown_key", replace("reflectance:", "reflectanse:"), "reflectanse"},
        {"missing_mesh", replace("{type: sphere, center: [0, 0, 0], radius: 1, material: white}",
                                 "{type: mesh, file: nowhere.obj, material: white}"),
         "nowhere.obj"},
        {"nan_matrix", replace("{look_at: {origin: [0, 0, -3], target: [0, 0, 0], up: [0, 1, 0]}}",
                               "{matrix: [1, 0, 0, 0, 0, .nan, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}"),
         "to_world"},
        {"degenerate_triangles", replace("{type: sphere, center: [0, 0, 0], radius: 1, material: white}",
                                         "{type: mesh, file: degenerate.obj, material: white}"),
         "degenerate"},
        {"wrong_type", replace("fov: 40", "fov: wide"), "fov"},
    };
    for (const auto& c : cases) {
        std::string scene = write("bad.yaml", c.text);
        CmdResult r = run("render " + scene + " -o " + (dir_ / "bad.exr").string() + " --spp 1");
        EXPECT_EQ(r.code, 2) << c.name << ": " << r.output;
        EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.name << ": " << r.output;
        // file:line: is always there
        EXPECT_NE(r.output.find("bad.yaml:"), std::string::npos) << c.name << ": " << r.output;
        EXPECT_EQ(r.output.find("internal error"), std::string::npos) << c.name << ": " << r.output;
    }
}

TEST_F(CliTest, UsageErrorsExitWithCodeTwo) {
    EXPECT_EQ(run("render").code, 2);
    EXPECT_EQ(run("render x.yaml --spp -3").code, 2);
    EXPECT_EQ(run("frobnicate").code, 2);
    EXPECT_EQ(run("render /nonexistent/scene.yaml").code, 2);
}

}  // namespace
