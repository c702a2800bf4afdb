// `omega render` as a user runs it: exit codes, messages naming file:line: key, and the EXR.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "film/film.h"
#include "run_omega.h"

namespace fs = std::filesystem;

namespace {

using CmdResult = omega::test::OmegaResult;
CmdResult run(const std::string& args) { return omega::test::run_omega(args); }

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
    EXPECT_EQ(img.attributes["omega.sampler"], "sobol");  // the default
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
                                         "{type: mesh, file: degenerate.obj, material: white, drop_degenerate: false}"),
         "degenerate"},
        {"only_degenerate_triangles", replace("{type: sphere, center: [0, 0, 0], radius: 1, material: white}",
                                              "{type: mesh, file: degenerate.obj, material: white}"),
         "no triangles left"},
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

// `omega render --samples` on "different machines" and `omega merge`: the merged file equals the
// single render within the documented 1e-6 relative; parts of a changed scene are refused.
TEST_F(CliTest, PartsRenderedApartMergeToTheSingleRender) {
    std::string scene = write("parts.yaml", kGood);
    auto path = [&](const char* name) { return (dir_ / name).string(); };
    for (const char* integrator : {"path", "bdpt"}) {
        const std::string common = " --seed 3 --threads 2 -q --integrator " + std::string(integrator);
        ASSERT_EQ(run("render " + scene + " --spp 9 -o " + path("whole.exr") + common).code, 0);
        ASSERT_EQ(run("render " + scene + " --samples 0:2 -o " + path("p0.exr") + common).code, 0);
        ASSERT_EQ(run("render " + scene + " --samples 2:7 -o " + path("p1.exr") + common).code, 0);
        CmdResult last = run("render " + scene + " --samples 7:9 -o " + path("p2.exr") + common);
        ASSERT_EQ(last.code, 0) << last.output;
        CmdResult m = run("merge " + path("p2.exr") + " " + path("p0.exr") + " " + path("p1.exr") + " -o " +
                          path("merged.exr"));
        ASSERT_EQ(m.code, 0) << m.output;
        EXPECT_NE(m.output.find("3 part(s), samples 0:9 (9 spp)"), std::string::npos) << m.output;
        omega::ExrImage whole = omega::read_exr(path("whole.exr")), merged = omega::read_exr(path("merged.exr"));
        EXPECT_EQ(merged.attributes["omega.spp"], "9");
        EXPECT_EQ(merged.attributes["omega.samples"], "0:9");
        EXPECT_EQ(merged.attributes["omega.integrator"], integrator);
        EXPECT_EQ(merged.attributes["omega.sampler"], "sobol");
        ASSERT_EQ(whole.rgb.size(), merged.rgb.size());
        ASSERT_EQ(whole.var.size(), merged.var.size());
        for (auto [a, b] : {std::pair{&whole.rgb, &merged.rgb}, std::pair{&whole.var, &merged.var}})
            for (size_t i = 0; i < a->size(); ++i)
                EXPECT_LE(std::abs((*a)[i] - (*b)[i]), 1e-6f * std::max(std::abs((*a)[i]), std::abs((*b)[i])))
                    << integrator << " value " << i;
        EXPECT_GT(whole.rgb[3 * (6 * 16 + 8)], 0.f);
    }
    // A part of another scene (one reflectance changed) is refused, naming the file.
    std::string changed = kGood;
    changed.replace(changed.find("0.5, 0.5, 0.5"), 13, "0.6, 0.5, 0.5");
    ASSERT_EQ(run("render " + write("changed.yaml", changed) + " --samples 2:7 --seed 3 -q -o " + path("c1.exr")).code, 0);
    CmdResult bad = run("merge " + path("p0.exr") + " " + path("c1.exr") + " -o " + path("bad.exr"));
    EXPECT_EQ(bad.code, 2) << bad.output;
    EXPECT_NE(bad.output.find("c1.exr: scene hash"), std::string::npos) << bad.output;
    // A part made with the other sampler (p0.exr is bdpt now) is refused, naming it; --sampler
    // reaches the header.
    ASSERT_EQ(
        run("render " + scene + " --samples 2:7 --seed 3 -q --integrator bdpt --sampler independent -o " + path("i1.exr"))
            .code,
        0);
    EXPECT_EQ(omega::read_exr(path("i1.exr")).attributes["omega.sampler"], "independent");
    CmdResult mixed = run("merge " + path("p0.exr") + " " + path("i1.exr") + " -o " + path("bad.exr"));
    EXPECT_EQ(mixed.code, 2) << mixed.output;
    EXPECT_NE(mixed.output.find("i1.exr: sampler independent differs"), std::string::npos) << mixed.output;
    EXPECT_EQ(run("render " + scene + " --spp 2 --sampler halton -q -o " + path("bad.exr")).code, 2);
    // Overlaps and gaps are refused; a plain render is not a part; a bad range is a usage error.
    EXPECT_EQ(run("merge " + path("p0.exr") + " " + path("p0.exr") + " -o " + path("bad.exr")).code, 2);
    CmdResult gap = run("merge " + path("p0.exr") + " " + path("p2.exr") + " -o " + path("gap.exr"));
    EXPECT_EQ(gap.code, 2);
    EXPECT_NE(gap.output.find("2:7 are in no part"), std::string::npos) << gap.output;
    EXPECT_EQ(run("merge " + path("p0.exr") + " " + path("p2.exr") + " --allow-gaps -q -o " + path("gap.exr")).code, 0);
    EXPECT_EQ(omega::read_exr(path("gap.exr")).attributes["omega.gaps"], "2:7");
    CmdResult plain = run("merge " + path("whole.exr") + " " + path("p0.exr") + " -o " + path("bad.exr"));
    EXPECT_EQ(plain.code, 2);
    EXPECT_NE(plain.output.find("not a partial render"), std::string::npos) << plain.output;
    EXPECT_FALSE(fs::exists(path("bad.exr")));
    EXPECT_EQ(run("render " + scene + " --samples 5:5 -o " + path("x.exr")).code, 2);
    EXPECT_EQ(run("render " + scene + " --samples 0:4 --spp 4 -o " + path("x.exr")).code, 2);
}

// A mesh as exported (one zero-area triangle among good ones) renders, with one warning on stderr
// and in the EXR header.
TEST_F(CliTest, DegenerateTrianglesAreDroppedWithAWarning) {
    write("quad.obj", "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv 0 -1 0\nf 1 2 3\nf 1 3 4\nf 1 5 2\n");
    std::string text = kGood;
    const std::string sphere = "{type: sphere, center: [0, 0, 0], radius: 1, material: white}";
    text.replace(text.find(sphere), sphere.size(), "{type: mesh, name: Panel, file: quad.obj, material: white}");
    std::string scene = write("mesh.yaml", text);
    std::string out = (dir_ / "mesh.exr").string();
    CmdResult r = run("render " + scene + " -o " + out + " --spp 1 -q");
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string w = "shapes[0] 'Panel' (quad.obj): 1 degenerate (zero-area) triangle dropped";
    EXPECT_NE(r.output.find("warning: "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(w), std::string::npos) << r.output;
    EXPECT_NE(omega::read_exr(out).attributes["omega.warnings"].find(w), std::string::npos);
}

TEST_F(CliTest, UsageErrorsExitWithCodeTwo) {
    EXPECT_EQ(run("render").code, 2);
    EXPECT_EQ(run("render x.yaml --spp -3").code, 2);
    EXPECT_EQ(run("frobnicate").code, 2);
    EXPECT_EQ(run("render /nonexistent/scene.yaml").code, 2);
}

}  // namespace

namespace {

CmdResult shell(const std::string& command) { return omega::test::run_shell(command); }

}  // namespace

// OpenImageIO lives in libomega_images.so, opened when a command first needs an image
// (io/image_library.h): omega does not load it at start, a command that needs it gets it, and
// one that cannot load it fails alone with a message naming where it looked.
TEST_F(CliTest, ImageLibraryLoadsOnlyWhenAnImageIsNeeded) {
    CmdResult deps = shell("ldd " + std::string(OMEGA_BIN));
    ASSERT_EQ(deps.code, 0) << deps.output;
    EXPECT_EQ(deps.output.find("OpenImageIO"), std::string::npos) << deps.output;

    std::string scene = write("good.yaml", kGood);
    std::string out = (dir_ / "out.exr").string();
    ASSERT_EQ(run("render " + scene + " -o " + out + " --spp 2 -q").code, 0);
    CmdResult same = run("compare " + out + " " + out);
    EXPECT_EQ(same.code, 0) << same.output;
    EXPECT_NE(same.output.find("RMSE 0 "), std::string::npos) << same.output;

    const std::string missing = (dir_ / "no-such-libomega_images.so").string();
    CmdResult refused = shell("OMEGA_IMAGE_LIBRARY=" + missing + " " + OMEGA_BIN + " compare " + out + " " + out);
    EXPECT_EQ(refused.code, 2) << refused.output;
    EXPECT_NE(refused.output.find("cannot load the image library libomega_images.so"), std::string::npos) << refused.output;
    EXPECT_NE(refused.output.find(missing + ": not there"), std::string::npos) << refused.output;
    // A module someone else could replace is refused; the same file kept to its owner is used.
    const fs::path copy = dir_ / "libomega_images.so";
    fs::copy_file(OMEGA_IMAGES_MODULE, copy);
    fs::permissions(copy, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read | fs::perms::group_write |
                              fs::perms::others_read);
    CmdResult writable = shell("OMEGA_IMAGE_LIBRARY=" + copy.string() + " " + OMEGA_BIN + " compare " + out + " " + out);
    EXPECT_EQ(writable.code, 2) << writable.output;
    EXPECT_NE(writable.output.find("writable by others or owned by another user, refused"), std::string::npos)
        << writable.output;
    fs::permissions(copy, fs::perms::group_write, fs::perm_options::remove);
    CmdResult kept = shell("OMEGA_IMAGE_LIBRARY=" + copy.string() + " " + OMEGA_BIN + " compare " + out + " " + out);
    EXPECT_EQ(kept.code, 0) << kept.output;
    // Rendering an untextured scene needs no image library at all.
    CmdResult render = shell("OMEGA_IMAGE_LIBRARY=" + missing + " " + OMEGA_BIN + " render " + scene + " -o " + out +
                             " --spp 1 -q");
    EXPECT_EQ(render.code, 0) << render.output;
}
