#include "breakdown_output.h"

#include <fmt/format.h>

#include <filesystem>
#include <fstream>

#include "breakdown_chart.h"

namespace omega {

std::string breakdown_path(const std::string& exr_path, const std::string& ext) {
    std::filesystem::path p(exr_path);
    return (p.parent_path() / (p.stem().string() + ".breakdown." + ext)).string();
}

int write_breakdown_files(const BreakdownReport& r, const std::string& exr_path, const std::string& csv_path) {
    const std::string csv = csv_path.empty() ? breakdown_path(exr_path, "csv") : csv_path;
    std::ofstream f(csv);
    f << breakdown_csv(r);
    if (!f.flush()) {
        fmt::print(stderr, "omega: cannot write breakdown '{}'\n", csv);
        return 2;
    }
    const std::string png = breakdown_path(exr_path, "png");
    try {
        write_breakdown_chart(r, png);
    } catch (const std::exception& e) {
        fmt::print(stderr, "omega: breakdown chart: {}\n", e.what());
        return 2;
    }
    fmt::print("breakdown: {}, {}\n", csv, png);
    return 0;
}

}  // namespace omega
