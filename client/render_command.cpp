#include "render_command.h"

#include <fmt/format.h>

#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "breakdown_output.h"
#include "client_error.h"
#include "film/film.h"
#include "film/partial_exr.h"
#include "import_command.h"
#include "integrator/render_session.h"
#include "progress_bar.h"
#include "pathspace/classify.h"
#include "pathspace/lpe_classify.h"
#include "scene/scene.h"
#include "scene/scene_error.h"
#include "scene/mitsuba_importer.h"
#include "scene/scene_parser.h"
#include "scene_hash.h"
#include "session_outputs.h"

namespace omega {

namespace {

// When this process started, on the steady clock: a user's `--time` budget includes what ran
// before main (the dynamic linker; 0.3 s when OpenImageIO was linked in, see io/image_library.h). From
// /proc/self/stat (field 22, clock ticks since boot); now where that cannot be read.
std::chrono::steady_clock::time_point process_start() {
    const auto now = std::chrono::steady_clock::now();
    std::ifstream stat("/proc/self/stat");
    std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
    const auto paren = text.rfind(')');  // the command name may hold spaces
    timespec boot{};
    if (paren == std::string::npos || clock_gettime(CLOCK_BOOTTIME, &boot) != 0) return now;
    std::istringstream fields(text.substr(paren + 2));
    std::string field;
    for (int i = 3; i < 22 && fields >> field; ++i) {
    }
    unsigned long long ticks = 0;
    if (!(fields >> ticks)) return now;
    const double age = double(boot.tv_sec) + double(boot.tv_nsec) * 1e-9 - double(ticks) / double(sysconf(_SC_CLK_TCK));
    if (!(age >= 0 && age < 60)) return now;
    return now - std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(age));
}

// Seconds to compress and write the EXR (R, G, B, var.*), kept back from a time budget.
// Measured: 1024² in about 0.45 s on 2 threads, i.e. about 0.85 µs per pixel and thread.
double expected_write_s(long long pixels, int threads) { return 0.85e-6 * double(pixels) / double(std::max(1, threads)); }

}  // namespace


namespace {


std::string default_output(const std::string& scene) {
    return std::filesystem::path(scene).stem().string() + ".exr";
}

std::string human_rate(double v) {
    if (v >= 1e9) return fmt::format("{:.2f}G", v / 1e9);
    if (v >= 1e6) return fmt::format("{:.2f}M", v / 1e6);
    if (v >= 1e3) return fmt::format("{:.1f}k", v / 1e3);
    return fmt::format("{:.0f}", v);
}

}  // namespace

void add_render_command(CLI::App& app, RenderArgs& a) {
    auto* cmd = app.add_subcommand("render", "Render a scene locally to an EXR file");
    cmd->add_option("scene", a.scene, "Scene file (YAML format v1, Mitsuba XML: *.xml, or glTF 2.0: *.gltf, *.glb)")->required();
    cmd->add_option("-o,--output", a.output, "Output EXR (default: the scene's name with .exr)");
    auto* spp = cmd->add_option("--spp", a.spp, "Samples per pixel")->check(CLI::PositiveNumber);
    auto* time = cmd->add_option("--time", a.time_s, "Render for this many seconds")->check(CLI::PositiveNumber);
    auto* err = cmd->add_option("--target-error", a.target_error, "Stop at this estimated relative error")
                    ->check(CLI::PositiveNumber);
    auto* samples = cmd->add_option("--samples", a.samples,
                                    "A:B: render only sample indices [A, B) of every pixel, into a partial EXR that "
                                    "`omega merge` combines exactly with the other ranges");
    spp->excludes(time)->excludes(err)->excludes(samples);
    time->excludes(err)->excludes(samples);
    err->excludes(samples);
    cmd->add_option("--integrator", a.integrator, "path | light | bdpt (overrides the scene)")
        ->check(CLI::IsMember({"path", "light", "bdpt"}));
    cmd->add_option("--sampler", a.sampler, "sobol | independent (overrides the scene's sampler; default sobol)")
        ->check(CLI::IsMember({"sobol", "independent"}));
    cmd->add_option("--threads", a.threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
    cmd->add_option("--seed", a.seed, "Random seed (default 0)");
    cmd->add_option("--report", a.report_csv, "Write one CSV row per pass to this file");
    cmd->add_flag("-q,--quiet", a.quiet, "No progress output");
    cmd->add_option("--strategies", a.strategies,
                    "light/bdpt: also write each (s,t) strategy's weighted and unweighted image as EXR layers "
                    "sSTt.weighted/.unweighted, for path lengths up to this")
        ->check(CLI::Range(1, 12))
        ->excludes(samples);
    cmd->add_option("-D,--define", a.defines, "Mitsuba XML scenes: set a <default> variable, name=value (repeatable)");
    cmd->add_option("--aov", a.aovs,
                    "Also write the light carried by the paths a light path expression matches, as EXR layers "
                    "aov.NAME.R/G/B and aov.NAME.var.R/G/B: NAME=EXPR, e.g. caustics='L S+ D E' (repeatable; "
                    "replaces a scene aov of the same name; see docs/scene-format.md)");
    cmd->add_flag("--breakdown", a.breakdown,
                  "Estimate how much of the image each path class (L, S, D, E) and each path length carries, "
                  "with standard errors: a table, NAME.breakdown.csv, NAME.breakdown.png and the EXR header "
                  "attribute omega.breakdown (docs/breakdown.md)");
    cmd->add_option("--breakdown-length", a.breakdown_length,
                    "--breakdown: classes up to this many edges; longer paths form one row (default 6)")
        ->check(CLI::Range(1, kMaxBreakdownLength));
    cmd->add_option("--breakdown-box", a.breakdown_box,
                    "--breakdown: measure the pixel box x0,y0,x1,y1 ([x0, x1) x [y0, y1), inside the crop) "
                    "instead of the whole image");
    cmd->add_option("--breakdown-csv", a.breakdown_csv, "--breakdown: the CSV's path (default NAME.breakdown.csv)");
    cmd->add_option("--camera", a.camera, "glTF scenes: render this camera (node or camera name; default: the first)");
}

int run_render(const RenderArgs& a) {
    // `--time` is the user's budget for the whole command: loading the scene counts.
    const auto started = process_start();
    SceneDesc desc;
    std::unique_ptr<Scene> scene;
    MitsubaOptions xml;
    if (!parse_defines(a.defines, xml.defines)) return 2;
    xml.camera = a.camera;
    std::optional<SampleRange> range;
    if (!a.samples.empty()) {
        try {
            range = parse_sample_range(a.samples);
        } catch (const std::invalid_argument& e) {
            fmt::print(stderr, "omega: --samples: {}\n", e.what());
            return 2;
        }
    }
    try {
        desc = load_scene_file(a.scene, xml);
        if (a.integrator == "path") desc.integrator.type = IntegratorType::Path;
        if (a.integrator == "light") desc.integrator.type = IntegratorType::Light;
        if (a.integrator == "bdpt") desc.integrator.type = IntegratorType::Bdpt;
        if (auto s = sampler_from_name(a.sampler)) desc.integrator.sampler = *s;
        for (const std::string& arg : a.aovs) set_aov(desc.sensor.film.aovs, parse_aov_arg(arg));
        if (desc.sensor.film.aovs.size() > size_t(kMaxAovs))
            throw std::invalid_argument(fmt::format("--aov: at most {} aovs per film", kMaxAovs));
        scene = Scene::build(desc);
    } catch (const SceneError& e) {
        fmt::print(stderr, "omega: {}\n", e.what());
        return 2;
    } catch (const std::invalid_argument& e) {  // --aov
        fmt::print(stderr, "omega: {}\n", e.what());
        return 2;
    }
    // What the scene can produce but this integrator cannot sample, in full-path notation.
    for (const auto& w : scene->warnings()) desc.warnings.push_back(w);
    for (auto& w : path_space_warnings(*scene, desc.integrator.type)) desc.warnings.push_back(std::move(w));
    for (auto& w : aov_warnings(*scene, LpeSet(desc.sensor.film.aovs), desc.integrator.type))
        desc.warnings.push_back(std::move(w));
    for (const auto& w : desc.warnings) fmt::print(stderr, "omega: warning: {}\n", w);

    // Hashed before rendering, so an unreadable file fails now rather than after the render.
    std::string scene_hash;
    if (range) {
        try {
            scene_hash = client::scene_content_hash(a.scene, desc, a.defines);
        } catch (const client::ClientError& e) {
            fmt::print(stderr, "omega: {}\n", e.what());
            return e.exit_code();
        }
    }

    RenderSettings rs;
    rs.halt = desc.sensor.halt;
    if (a.spp || a.time_s || a.target_error) rs.halt = HaltDesc{a.spp, a.time_s, a.target_error};
    // A part starts on an empty film at sample A, exactly as a resumed render continues at it.
    if (range) {
        rs.halt = HaltDesc{range->end, std::nullopt, std::nullopt};
        rs.first_sample = range->begin;
    }
    rs.threads = a.threads;
    rs.time_origin = started;
    if (rs.halt.time_s) {
        // Keep back the time the output takes to write, at most a quarter of the budget.
        const double write_s = expected_write_s(1LL * desc.sensor.film.width * desc.sensor.film.height, resolve_threads(a.threads));
        rs.halt.time_s = *rs.halt.time_s - std::min(write_s, 0.25 * *rs.halt.time_s);
    }
    rs.seed = a.seed;
    rs.integrator = desc.integrator;
    rs.strategy_images_max_k = a.strategies;
    if (a.breakdown || !a.breakdown_box.empty()) {
        BreakdownDesc bd;
        bd.max_length = a.breakdown_length;
        if (!a.breakdown_box.empty()) {
            try {
                bd.box = parse_breakdown_box(a.breakdown_box);
            } catch (const std::invalid_argument& e) {
                fmt::print(stderr, "omega: --breakdown-box: {}\n", e.what());
                return 2;
            }
        }
        rs.breakdown = bd;
    }
    if (a.strategies > 0 && desc.integrator.type == IntegratorType::Path)
        fmt::print(stderr, "omega: warning: --strategies needs --integrator bdpt or light; ignored\n");

    std::unique_ptr<RenderSession> session;
    try {
        session = std::make_unique<RenderSession>(*scene, rs);
    } catch (const std::invalid_argument& e) {
        fmt::print(stderr, "omega: {}: {}\n", a.scene, e.what());
        return 2;
    }

    std::ofstream csv;
    if (!a.report_csv.empty()) {
        csv.open(a.report_csv);
        if (!csv) {
            fmt::print(stderr, "omega: cannot write report '{}'\n", a.report_csv);
            return 2;
        }
        csv << "pass,spp,elapsed_s,samples_per_s,rays_per_s,rel_error,image_mean,image_mean_stderr,nonfinite\n";
    }

    ProgressBar bar(stderr);
    const HaltDesc& h = rs.halt;
    PassReport last = session->run([&](const PassReport& r) {
        if (csv)
            csv << fmt::format("{},{},{:.6f},{:.6g},{:.6g},{:.6g},{:.9g},{:.6g},{}\n", r.pass, r.spp, r.elapsed_s,
                               r.samples_per_s, r.rays_per_s, r.error.mean_rel_error, r.error.image_mean,
                               r.error.image_mean_stderr, r.nonfinite)
                << std::flush;
        if (a.quiet) return;
        double frac = -1;
        if (h.spp) frac = double(r.spp - rs.first_sample) / double(*h.spp - rs.first_sample);
        else if (h.time_s) frac = r.elapsed_s / *h.time_s;
        else if (!h.target_error) frac = double(r.spp) / 64.0;
        bar.update(frac, fmt::format("{} spp  {:.1f}s  err {:.4f}  {} samples/s{}", r.spp, r.elapsed_s,
                                     r.error.mean_rel_error, human_rate(r.samples_per_s),
                                     r.nonfinite ? fmt::format("  nonfinite {}", r.nonfinite) : ""));
    });
    bar.finish();

    std::string out = a.output.empty() ? default_output(a.scene) : a.output;
    set_exr_threads(resolve_threads(a.threads));  // the workers are idle now: compress in parallel
    ExrMeta meta;
    meta.spp = last.spp - rs.first_sample;
    meta.time_s = last.elapsed_s;
    meta.integrator = integrator_name(desc.integrator.type);
    meta.seed = a.seed;
    meta.attributes["omega.sampler"] = sampler_name(desc.integrator.sampler);
    meta.nonfinite = last.nonfinite;
    meta.warnings = desc.warnings;
    meta.rel_error = last.error.mean_rel_error;
    if (const StrategyImages* si = session->strategy_images()) meta.layers = si->layers(last.spp);
    const std::vector<AovFilm>& aovs = session_aov_films(*session);
    const std::optional<BreakdownReport> breakdown =
        add_session_outputs(*session, rs.first_sample, last.spp, range.has_value(), meta);
    try {
        if (range) {
            PartInfo part{{{range->begin, last.spp}}, scene_hash, a.seed, meta.integrator,
                          sampler_name(desc.integrator.sampler)};
            write_partial_exr(out, session->film(), meta, part, aovs);
        } else {
            write_exr(out, session->film(), meta);
        }
    } catch (const std::exception& e) {
        fmt::print(stderr, "omega: {}\n", e.what());
        return 1;
    }
    if (breakdown) {
        fmt::print("{}", breakdown_table(*breakdown));
        const int rc = write_breakdown_files(*breakdown, out, a.breakdown_csv);
        if (rc != 0) return rc;
    }
    const std::string what = range ? fmt::format("samples {}:{} ({} spp)", range->begin, last.spp, meta.spp)
                                   : fmt::format("{} spp", last.spp);
    fmt::print("{}: {} in {:.2f} s, {} samples/s, {} rays/s, rel. error {:.4f}, {} non-finite\n", out, what,
               last.elapsed_s, human_rate(last.samples_per_s), human_rate(last.rays_per_s), last.error.mean_rel_error,
               last.nonfinite);
    return 0;
}

}  // namespace omega
