#pragma once
// `omega render`: renders a scene locally with the renderer library.
#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

namespace omega {

struct RenderArgs {
    std::string scene;
    std::string output;
    std::optional<long long> spp;
    std::optional<double> time_s;
    std::optional<double> target_error;
    std::string integrator;
    std::string sampler;  // sobol | independent; empty: the scene's
    int threads = 0;
    uint64_t seed = 0;
    std::string report_csv;
    bool quiet = false;
    int strategies = 0;  // > 0: write per-(s,t) layers for path lengths up to this
    std::vector<std::string> defines;  // -D name=value, for Mitsuba XML scenes
    std::string camera;                // --camera NAME, for glTF scenes
    std::string samples;  // "A:B": a partial render of sample indices [A, B), for `omega merge`
    std::vector<std::string> aovs;  // --aov NAME=EXPR (repeatable): light path expression outputs
    // --breakdown: the measurement by path class and length (docs/breakdown.md).
    bool breakdown = false;
    int breakdown_length = 6;
    std::string breakdown_box;  // "x0,y0,x1,y1"; empty: the whole crop
    std::string breakdown_csv;  // empty: next to the output, NAME.breakdown.csv
};

void add_render_command(CLI::App& app, RenderArgs& args);
// Returns the process exit code (0 ok, 1 internal error, 2 bad input).
int run_render(const RenderArgs& args);

}  // namespace omega
