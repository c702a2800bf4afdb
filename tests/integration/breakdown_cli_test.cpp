// `omega render --breakdown` as a user runs it: the table, NAME.breakdown.csv, the chart
// NAME.breakdown.png and the EXR header attribute omega.breakdown; a pixel box; bad boxes.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "film/film.h"
#include "integrator/breakdown.h"
#include "run_omega.h"
#include "scene_dir_fixture.h"

namespace fs = std::filesystem;

namespace omega {
namespace {

std::string read_file(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

// Width and height from a PNG's IHDR chunk (0 x 0 if the file is no PNG).
std::pair<uint32_t, uint32_t> png_size(const std::string& bytes) {
    if (bytes.size() < 24 || bytes.compare(1, 3, "PNG") != 0 || bytes.compare(12, 4, "IHDR") != 0) return {0, 0};
    auto be32 = [&](size_t at) {
        uint32_t v = 0;
        for (size_t i = 0; i < 4; ++i) v = (v << 8) | uint8_t(bytes[at + i]);
        return v;
    };
    return {be32(16), be32(20)};
}

class BreakdownCli : public test::SceneDirTest {
protected:
    BreakdownCli() : SceneDirTest("omega_breakdown_cli_", test::kMirrorSphereScene) {}
};

TEST_F(BreakdownCli, WritesTableCsvChartAndHeader) {
    for (const char* integrator : {"path", "bdpt"}) {
        const std::string out = path(std::string(integrator) + ".exr");
        auto r = test::run_omega("render " + scene_ + " -o " + out + " --spp 4 --threads 2 -q --breakdown --integrator " +
                                 integrator);
        ASSERT_EQ(r.code, 0) << r.output;
        EXPECT_NE(r.output.find("L D E"), std::string::npos) << r.output;  // the table
        const std::string csv = read_file(path(std::string(integrator) + ".breakdown.csv"));
        const BreakdownReport rep = parse_breakdown_csv(csv);
        EXPECT_EQ(rep.region, "image");
        EXPECT_FALSE(rep.of_kind("class").empty());
        EXPECT_EQ(rep.of_kind("total").size(), 1u);
        // The header carries the same report.
        const ExrImage img = read_exr(out);
        auto it = img.attributes.find("omega.breakdown");
        ASSERT_NE(it, img.attributes.end());
        EXPECT_EQ(it->second, csv);
        // The chart is a PNG with room for its bars and legend.
        const auto [w, h] = png_size(read_file(path(std::string(integrator) + ".breakdown.png")));
        EXPECT_GE(w, 200u);
        EXPECT_GE(h, 200u);
    }
}

TEST_F(BreakdownCli, BoxAndCsvPath) {
    const std::string csv = path("box.csv");
    auto r = test::run_omega("render " + scene_ + " -o " + path("b.exr") +
                             " --spp 2 -q --breakdown --breakdown-box 4,3,12,9 --breakdown-length 1 --breakdown-csv " + csv);
    ASSERT_EQ(r.code, 0) << r.output;
    const BreakdownReport rep = parse_breakdown_csv(read_file(csv));
    EXPECT_EQ(rep.region, "box:4:3:12:9");
    bool longer = false;
    for (const auto& row : rep.rows) {
        EXPECT_LE(row.length, kMaxBreakdownLength + 1);
        if (row.kind == "class" && row.length <= kMaxBreakdownLength) {
            EXPECT_LE(row.length, 1) << row.name;
        }
        longer = longer || row.name == "longer";
    }
    EXPECT_TRUE(longer) << "the direct light (2 edges) goes in the longer row";
}

TEST_F(BreakdownCli, BadBoxExitsTwo) {
    for (const char* box : {"0,0,17,5", "5,5,5,8", "1,2,3", "a,b,c,d"}) {
        auto r = test::run_omega("render " + scene_ + " -o " + path("x.exr") + " --spp 1 -q --breakdown-box " + box);
        EXPECT_EQ(r.code, 2) << box << ": " << r.output;
        EXPECT_NE(r.output.find("breakdown box"), std::string::npos) << r.output;
        EXPECT_FALSE(fs::exists(path("x.exr")));
    }
}

// Parts carry their range's exact sums: merged, they give the breakdown of one render of the
// whole range, digit for digit. A part without one cannot be combined: a warning, and none.
TEST_F(BreakdownCli, MergeAddsPartBreakdownsExactly) {
    const std::string common = " -q --breakdown --threads 2";
    ASSERT_EQ(test::run_omega("render " + scene_ + " --spp 4 -o " + path("whole.exr") + common).code, 0);
    ASSERT_EQ(test::run_omega("render " + scene_ + " --samples 0:3 -o " + path("p0.exr") + common).code, 0);
    ASSERT_EQ(test::run_omega("render " + scene_ + " --samples 3:4 -o " + path("p1.exr") + common).code, 0);
    ASSERT_EQ(test::run_omega("render " + scene_ + " --samples 3:4 -q -o " + path("plain.exr")).code, 0);
    auto m = test::run_omega("merge " + path("p1.exr") + " " + path("p0.exr") + " -o " + path("m.exr"));
    ASSERT_EQ(m.code, 0) << m.output;
    const auto whole = read_exr(path("whole.exr")).attributes, merged = read_exr(path("m.exr")).attributes;
    ASSERT_TRUE(merged.count("omega.breakdown")) << m.output;
    EXPECT_EQ(merged.at("omega.breakdown"), whole.at("omega.breakdown"));
    EXPECT_NE(read_exr(path("p0.exr")).attributes.at("omega.breakdown"), whole.at("omega.breakdown"));

    auto d = test::run_omega("merge " + path("p0.exr") + " " + path("plain.exr") + " -o " + path("d.exr"));
    ASSERT_EQ(d.code, 0) << d.output;
    EXPECT_NE(d.output.find("breakdowns are not merged"), std::string::npos) << d.output;
    EXPECT_FALSE(read_exr(path("d.exr")).attributes.count("omega.breakdown"));
}

// converge --breakdown: per-class columns per checkpoint, and the line naming the class that
// holds the largest share of the error.
TEST_F(BreakdownCli, ConvergeWritesPerClassColumns) {
    const std::string out = path("conv");
    auto r = test::run_omega("converge " + scene_ + " --no-reference --budget 1 --runs 1 --integrators path --threads 2 "
                             "--breakdown --breakdown-classes 2 --out-dir " + out);
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("of the energy and"), std::string::npos) << r.output;
    std::istringstream wide(read_file(out + "/path_classes_mean.csv"));
    std::string header, row;
    ASSERT_TRUE(std::getline(wide, header));
    EXPECT_EQ(header.rfind("time_target_s,time_s,all,L D E", 0), 0u) << header;  // L D E carries the most here
    ASSERT_TRUE(std::getline(wide, row));
    EXPECT_EQ(std::count(row.begin(), row.end(), ','), std::count(header.begin(), header.end(), ',')) << row;
    const std::string lines = read_file(out + "/path_classes.csv");
    EXPECT_EQ(lines.rfind("run,seed,time_target_s,time_s,spp,class,energy_fraction,relvar,error_fraction\n", 0), 0u);
    EXPECT_NE(lines.find(",L D E,"), std::string::npos) << lines;
}

}  // namespace
}  // namespace omega
