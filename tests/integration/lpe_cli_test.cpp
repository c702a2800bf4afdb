// Light path expression outputs through the command line: the film key `aov` and `--aov` give
// EXR layers aov.NAME (with .var) that partition the beauty, a warning for an expression no
// path can match, parse errors with the column, and parts that merge to the single render.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "film/film.h"
#include "run_omega.h"
#include "scene_dir_fixture.h"

namespace fs = std::filesystem;

namespace omega {
namespace {

// The rest of the partition `direct` starts.
const std::string kAovArgs = " --aov 'indirect=L D D+ E' --aov 'specular=L .* S .* E' --aov 'emitted=L E'";

class LpeCli : public test::SceneDirTest {
protected:
    LpeCli() : SceneDirTest("omega_lpe_cli_", test::kMirrorSphereScene) {}
};

TEST_F(LpeCli, LayersPartitionTheBeauty) {
    for (const char* integrator : {"path", "light", "bdpt"}) {
        const std::string out = path(std::string(integrator) + ".exr");
        auto r = test::run_omega("render " + scene_ + " -o " + out + " --spp 8 --threads 2 -q --integrator " +
                                 integrator + kAovArgs);
        ASSERT_EQ(r.code, 0) << r.output;
        const ExrImage beauty = read_exr(out);
        std::vector<double> sum(beauty.rgb.size(), 0.0), mag(beauty.rgb.size(), 0.0);
        for (const char* name : {"direct", "indirect", "specular", "emitted"}) {
            const std::vector<float> mean = read_exr_layer(out, std::string("aov.") + name);
            const std::vector<float> var = read_exr_layer(out, std::string("aov.") + name + ".var");
            ASSERT_EQ(mean.size(), beauty.rgb.size());
            ASSERT_EQ(var.size(), beauty.rgb.size());
            for (size_t i = 0; i < mean.size(); ++i) {
                ASSERT_TRUE(std::isfinite(mean[i]) && std::isfinite(var[i]) && var[i] >= 0) << name;
                sum[i] += mean[i];
                mag[i] += std::abs(mean[i]);
            }
        }
        double total = 0;
        for (size_t i = 0; i < sum.size(); ++i) {
            EXPECT_LE(std::abs(sum[i] - beauty.rgb[i]), 1e-5 * (mag[i] + std::abs(beauty.rgb[i])) + 1e-12)
                << integrator << " value " << i;
            total += beauty.rgb[i];
        }
        EXPECT_GT(total, 0.0) << integrator;
    }
}

TEST_F(LpeCli, WarnsAndRefuses) {
    // A point light seen in the mirror by the pinhole: L S D S D S E, no DD edge.
    auto w = test::run_omega("render " + scene_ + " -o " + path("w.exr") + " --spp 1 -q --aov 'seen=L S E'");
    EXPECT_EQ(w.code, 0) << w.output;
    EXPECT_NE(w.output.find("warning: aov seen (L S E): black"), std::string::npos) << w.output;
    EXPECT_NE(w.output.find("Theorem 8.3"), std::string::npos) << w.output;
    auto bad = test::run_omega("render " + scene_ + " -o " + path("b.exr") + " --spp 1 -q --aov 'x=L (S E'");
    EXPECT_EQ(bad.code, 2);
    EXPECT_NE(bad.output.find("column"), std::string::npos) << bad.output;
    auto name = test::run_omega("render " + scene_ + " -o " + path("b.exr") + " --spp 1 -q --aov 'a.b=L E'");
    EXPECT_EQ(name.code, 2);
    EXPECT_NE(name.output.find("aov name 'a.b'"), std::string::npos) << name.output;
    EXPECT_FALSE(fs::exists(path("b.exr")));
}

TEST_F(LpeCli, PartsMergeToTheSingleRender) {
    for (const char* integrator : {"path", "bdpt"}) {
        const std::string common = std::string(" --seed 3 --threads 2 -q --integrator ") + integrator + kAovArgs;
        ASSERT_EQ(test::run_omega("render " + scene_ + " --spp 7 -o " + path("whole.exr") + common).code, 0);
        ASSERT_EQ(test::run_omega("render " + scene_ + " --samples 0:3 -o " + path("p0.exr") + common).code, 0);
        ASSERT_EQ(test::run_omega("render " + scene_ + " --samples 3:7 -o " + path("p1.exr") + common).code, 0);
        auto m = test::run_omega("merge " + path("p1.exr") + " " + path("p0.exr") + " -o " + path("merged.exr"));
        ASSERT_EQ(m.code, 0) << m.output;
        for (const char* name : {"direct", "indirect", "specular", "emitted"}) {
            for (const char* suffix : {"", ".var"}) {
                const std::string layer = std::string("aov.") + name + suffix;
                const auto a = read_exr_layer(path("whole.exr"), layer), b = read_exr_layer(path("merged.exr"), layer);
                ASSERT_EQ(a.size(), b.size());
                // As for the beauty (docs/farm.md): 1e-6 relative, almost every value bit-identical.
                size_t identical = 0;
                for (size_t i = 0; i < a.size(); ++i) {
                    EXPECT_LE(std::abs(a[i] - b[i]), 1e-6 * std::abs(a[i]) + 1e-30) << integrator << " " << layer << " " << i;
                    identical += a[i] == b[i];
                }
                EXPECT_GE(double(identical), 0.95 * double(a.size())) << integrator << " " << layer;
            }
        }
        // A part without the AOVs does not merge with parts that have them.
        ASSERT_EQ(test::run_omega("render " + scene_ + " --samples 7:9 -o " + path("p2.exr") +
                                  std::string(" --seed 3 --threads 2 -q --integrator ") + integrator)
                      .code,
                  0);
        auto refused = test::run_omega("merge " + path("merged.exr") + " " + path("p2.exr") + " -o " + path("x.exr"));
        EXPECT_EQ(refused.code, 2);
        EXPECT_NE(refused.output.find("aovs"), std::string::npos) << refused.output;
    }
}

}  // namespace
}  // namespace omega
