// `omega import`, `omega render scene.xml` and `omega converge` as a user runs them.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "film/film.h"
#include "run_omega.h"

namespace fs = std::filesystem;

namespace {

using Result = omega::test::OmegaResult;
using omega::test::run_omega;

// A small lit box in Mitsuba 3 XML, with variables.
const char* kXml = R"(<scene version="3.0.0">
  <default name="res" value="16"/>
  <default name="max_depth" value="4"/>
  <integrator type="path"><integer name="max_depth" value="$max_depth"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, -3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
    <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$res"/><rfilter type="tent"/></film>
  </sensor>
  <bsdf type="twosided" id="white"><bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf></bsdf>
  <shape type="cube"><transform name="to_world"><scale value="0.5"/><rotate y="1" angle="30"/></transform><ref id="white"/></shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/><translate y="1.5"/></transform>
    <emitter type="area"><rgb name="radiance" value="5"/></emitter>
  </shape>
  <emitter type="constant"><rgb name="radiance" value="0.2"/></emitter>
</scene>
)";

class MitsubaCli : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / fs::path("omega_mitsuba_cli_" + std::to_string(::getpid()) + "_" +
                                                    ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_);
        xml_ = write("scene.xml", kXml);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string write(const std::string& name, const std::string& text) {
        fs::path p = dir_ / name;
        std::ofstream(p) << text;
        return p.string();
    }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    fs::path dir_;
    std::string xml_;
};

}  // namespace

TEST_F(MitsubaCli, ImportedYamlRendersTheSameImageAsTheXml) {
    Result imp = run_omega("import " + xml_ + " -o " + path("scene.yaml"));
    ASSERT_EQ(imp.code, 0) << imp.output;
    Result a = run_omega("render " + xml_ + " -q --spp 2 -o " + path("a.exr"));
    ASSERT_EQ(a.code, 0) << a.output;
    Result b = run_omega("render " + path("scene.yaml") + " -q --spp 2 -o " + path("b.exr"));
    ASSERT_EQ(b.code, 0) << b.output;
    omega::ExrImage ia = omega::read_exr(path("a.exr")), ib = omega::read_exr(path("b.exr"));
    EXPECT_EQ(ia.width, 16);
    EXPECT_EQ(ia.rgb, ib.rgb);
    double sum = 0;
    for (float v : ia.rgb) sum += v;
    EXPECT_GT(sum, 0);
}

TEST_F(MitsubaCli, DefinesOverrideDefaults) {
    Result r = run_omega("render " + xml_ + " -q --spp 1 -D res=8 -o " + path("a.exr"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_EQ(omega::read_exr(path("a.exr")).width, 8);
    Result bad = run_omega("render " + xml_ + " -q --spp 1 -D res -o " + path("a.exr"));
    EXPECT_EQ(bad.code, 2);
    EXPECT_NE(bad.output.find("-D res: expected name=value"), std::string::npos) << bad.output;
}

TEST_F(MitsubaCli, BadXmlIsExitCode2WithFileAndLine) {
    std::string bad = write("bad.xml", "<scene version=\"3.0.0\">\n<shape type=\"cube\">\n</scene>\n");
    for (const char* cmd : {"render ", "import "}) {
        Result r = run_omega(cmd + bad);
        EXPECT_EQ(r.code, 2) << r.output;
        EXPECT_NE(r.output.find("bad.xml:3: invalid XML"), std::string::npos) << r.output;
    }
}

TEST_F(MitsubaCli, ConvergeMeasuresEveryIntegrator) {
    Result r = run_omega("converge " + xml_ + " --integrators path,bdpt --budget 2 --runs 2 --reference-time 1 --threads 1 --out-dir " +
                     path("conv"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("no --reference: rendering one with the path tracer"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("is not available"), std::string::npos) << r.output;
    EXPECT_TRUE(fs::exists(path("conv/reference.exr")));
    EXPECT_TRUE(fs::exists(path("conv/bdpt.csv")));
    std::ifstream csv(path("conv/path.csv"));
    std::string header, row1, row2;
    std::getline(csv, header);
    std::getline(csv, row1);
    std::getline(csv, row2);
    EXPECT_EQ(header.rfind("time_target_s,runs,time_s,spp,rmse,rmse_sd,relmse", 0), 0u) << header;
    EXPECT_EQ(row1.rfind("1,2,", 0), 0u) << row1;
    EXPECT_EQ(row2.rfind("2,2,", 0), 0u) << row2;
    EXPECT_TRUE(fs::exists(path("conv/path_runs.csv")));
    EXPECT_TRUE(fs::exists(path("conv/convergence.gp")));
    if (std::system("command -v gnuplot > /dev/null 2>&1") == 0) {
        EXPECT_TRUE(fs::exists(path("conv/convergence.png")));
    }
}

TEST_F(MitsubaCli, ConvergeWithAnUnknownIntegratorIsExitCode2) {
    Result r = run_omega("converge " + xml_ + " --integrators photon --budget 1 --runs 1 --threads 1 --out-dir " +
                         path("conv"));
    EXPECT_EQ(r.code, 2) << r.output;
}

// --no-reference: the estimated relative variance per checkpoint, its slope, and the mode named.
TEST_F(MitsubaCli, ConvergeWithoutAReferenceReportsTheEstimatedVariance) {
    Result r = run_omega("converge " + xml_ + " --integrators path --budget 2 --runs 1 --threads 1 --no-reference --out-dir " +
                         path("var"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("mode: variance (no reference)"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("rendering one with the path tracer"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(path("var/reference.exr")));
    std::ifstream csv(path("var/path.csv"));
    std::string header, row1, row2;
    std::getline(csv, header);
    std::getline(csv, row1);
    std::getline(csv, row2);
    EXPECT_EQ(header, "time_target_s,runs,time_s,spp,relvar,relvar_sd,relvar_min,relvar_max,efficiency,efficiency_sd");
    EXPECT_EQ(row1.rfind("1,1,", 0), 0u) << row1;
    EXPECT_EQ(row2.rfind("2,1,", 0), 0u) << row2;
    // Pure Monte Carlo noise: the variance falls as 1/spp. Checked against the samples each
    // checkpoint holds, not its time: on a loaded machine (ctest -j, other builds) the second
    // second may render far fewer samples than the first, which bends the slope against time
    // (it read -0.4 once) without anything being wrong. The estimate of a 16 x 16 image's mean
    // variance is good to a few percent.
    EXPECT_NE(r.output.find("log-log slope "), std::string::npos) << r.output;
    auto field = [](const std::string& row, int i) {
        std::stringstream ss(row);
        std::string f;
        for (int k = 0; k <= i; ++k) std::getline(ss, f, ',');
        return std::stod(f);
    };
    const double spp1 = field(row1, 3), spp2 = field(row2, 3), var1 = field(row1, 4), var2 = field(row2, 4);
    ASSERT_GT(spp2, spp1) << row1 << "\n" << row2;
    const double ratio = (var1 / var2) / (spp2 / spp1);  // 1 for variance proportional to 1/spp
    EXPECT_GT(ratio, 0.7) << row1 << "\n" << row2;
    EXPECT_LT(ratio, 1.3) << row1 << "\n" << row2;
    Result bad = run_omega("converge " + xml_ + " --no-reference --reference-time 1 --budget 1 --out-dir " + path("var"));
    EXPECT_EQ(bad.code, 2) << bad.output;
}

// A textured diffuse reflectance through the importer: the YAML renders what the XML renders, and
// a texture file that cannot be decoded is a scene error (exit 2) naming the file.
TEST_F(MitsubaCli, TexturedSceneImportsAndBadTexturesAreExitCode2) {
    // A 2 x 2 binary PPM (8-bit, so sRGB-decoded).
    std::string ppm = "P6\n2 2\n255\n";
    ppm += std::string("\xff\x20\x10\x10\xff\x20\x20\x10\xff\x80\x80\x80", 12);
    write("tex.ppm", ppm);
    std::string xml = kXml;
    xml.replace(xml.find(R"(<rgb name="reflectance" value="0.5, 0.5, 0.5"/>)"),
                std::string(R"(<rgb name="reflectance" value="0.5, 0.5, 0.5"/>)").size(),
                R"(<texture type="bitmap" name="reflectance"><string name="filename" value="tex.ppm"/></texture>)");
    std::string tx = write("tex.xml", xml);
    Result imp = run_omega("import " + tx + " -o " + path("tex.yaml"));
    ASSERT_EQ(imp.code, 0) << imp.output;
    EXPECT_EQ(imp.output.find("average colour"), std::string::npos) << imp.output;
    Result a = run_omega("render " + tx + " -q --spp 2 -o " + path("a.exr"));
    ASSERT_EQ(a.code, 0) << a.output;
    Result b = run_omega("render " + path("tex.yaml") + " -q --spp 2 -o " + path("b.exr"));
    ASSERT_EQ(b.code, 0) << b.output;
    EXPECT_EQ(omega::read_exr(path("a.exr")).rgb, omega::read_exr(path("b.exr")).rgb);

    write("tex.ppm", "P6\ngarbage");
    Result bad = run_omega("render " + path("tex.yaml") + " -q --spp 1 -o " + path("c.exr"));
    EXPECT_EQ(bad.code, 2) << bad.output;
    EXPECT_NE(bad.output.find("reflectance: cannot read texture '"), std::string::npos) << bad.output;
    EXPECT_NE(bad.output.find("tex.ppm': not a valid ppm image"), std::string::npos) << bad.output;
    fs::remove(path("tex.ppm"));
    Result missing = run_omega("render " + path("tex.yaml") + " -q --spp 1 -o " + path("c.exr"));
    EXPECT_EQ(missing.code, 2) << missing.output;
    EXPECT_NE(missing.output.find("reflectance.file: cannot open"), std::string::npos) << missing.output;
}
