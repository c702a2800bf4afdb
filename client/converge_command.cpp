#include "converge_command.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>

#include "converge_breakdown.h"
#include "film/film.h"
#include "import_command.h"
#include "integrator/render_session.h"
#include "io/image_library.h"
#include "scene/mitsuba_importer.h"
#include "scene/scene.h"
#include "scene/scene_error.h"

namespace omega {

namespace fs = std::filesystem;

std::vector<double> converge_times(double budget_s) {
    std::vector<double> t;
    for (double x = 1; x < budget_s * (1 - 1e-9); x *= 2) t.push_back(x);
    t.push_back(budget_s);
    return t;
}

double loglog_slope(const std::vector<double>& x, const std::vector<double>& y) {
    std::vector<std::pair<double, double>> p;
    for (size_t i = 0; i < x.size() && i < y.size(); ++i)
        if (x[i] > 0 && y[i] > 0 && std::isfinite(x[i]) && std::isfinite(y[i])) p.emplace_back(std::log(x[i]), std::log(y[i]));
    if (p.size() < 2) return std::numeric_limits<double>::quiet_NaN();
    double mx = 0, my = 0;
    for (auto& [a, b] : p) mx += a, my += b;
    mx /= double(p.size());
    my /= double(p.size());
    double sxy = 0, sxx = 0;
    for (auto& [a, b] : p) sxy += (a - mx) * (b - my), sxx += (a - mx) * (a - mx);
    return sxx > 0 ? sxy / sxx : std::numeric_limits<double>::quiet_NaN();
}

namespace {

ImageError image_error(const ImagePixels& img, const ImagePixels& ref) {
    double v[4];
    if (std::string why = image_library().compare(img, ref, kRelMseEps, v); !why.empty()) throw std::runtime_error(why);
    return {v[0], v[1], v[2], v[3]};
}

// The first three channels of an image file, as float.
ImagePixels read_rgb(const std::string& path) {
    ImagePixels in;
    if (std::string why = image_library().read_file(path, in); !why.empty()) throw std::runtime_error(path + ": " + why);
    if (in.channels < 3) throw std::runtime_error(path + ": expected at least 3 channels (R, G, B)");
    if (in.channels == 3) return in;
    ImagePixels rgb{in.width, in.height, 3, true, std::vector<float>(size_t(in.width) * size_t(in.height) * 3)};
    for (size_t i = 0, n = size_t(in.width) * size_t(in.height); i < n; ++i)
        for (size_t c = 0; c < 3; ++c) rgb.data[i * 3 + c] = in.data[i * size_t(in.channels) + c];
    return rgb;
}

// Rows y0..y1, columns x0..x1 of an RGB image (the film's crop window of a full-frame reference).
ImagePixels cut(const ImagePixels& img, int x0, int y0, int x1, int y1) {
    ImagePixels out{x1 - x0, y1 - y0, 3, true, std::vector<float>(size_t(x1 - x0) * size_t(y1 - y0) * 3)};
    for (int y = y0; y < y1; ++y)
        std::copy_n(&img.data[(size_t(y) * size_t(img.width) + size_t(x0)) * 3], size_t(x1 - x0) * 3,
                    &out.data[size_t(y - y0) * size_t(x1 - x0) * 3]);
    return out;
}

// Downsamples a reference by an integer factor with OIIO's filtered resize, using the filter that
// matches the film's reconstruction filter (a tent-filtered render is compared with a
// tent-filtered reduction: measured on the Cornell box at 1/4 size, relMSE 0.0003 against 0.004
// for a box reduction, whose edges differ).
// A box film is compared with the exact k x k block average.
ImagePixels downsample(const ImagePixels& ref, int w, int h, FilterType f) {
    if (f == FilterType::Box) {
        const int k = ref.width / w;
        ImagePixels small{w, h, 3, true, std::vector<float>(size_t(w) * size_t(h) * 3, 0.f)};
        for (int y = 0; y < ref.height; ++y)
            for (int x = 0; x < ref.width; ++x)
                for (int c = 0; c < 3; ++c)
                    small.data[(size_t(y / k) * size_t(w) + size_t(x / k)) * 3 + size_t(c)] +=
                        ref.data[(size_t(y) * size_t(ref.width) + size_t(x)) * 3 + size_t(c)] / float(k * k);
        return small;
    }
    ImagePixels small;
    if (std::string why = image_library().resize(ref, w, h, f == FilterType::Tent ? "triangle" : "gaussian", small);
        !why.empty())
        throw std::runtime_error(why);
    return small;
}

const char* filter_word(FilterType f) {
    return f == FilterType::Tent ? "tent" : f == FilterType::Gaussian ? "gaussian" : "box";
}

ImagePixels film_image(const Film& film) {
    Rect c = film.crop();
    ImagePixels img{c.width(), c.height(), 3, true, std::vector<float>(size_t(c.width()) * size_t(c.height()) * 3)};
    size_t i = 0;
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            PixelStats p = film.pixel(x, y);
            for (int ch = 0; ch < 3; ++ch) img.data[i++] = float(p.mean[ch]);
        }
    return img;
}

struct Sample {
    int run = 0;
    uint64_t seed = 0;
    double target = 0, time_s = 0;
    long long spp = 0;
    ImageError err;
    double relvar = 0;
};

struct Summary {
    double target = 0;
    int n = 0;
    double time = 0, spp = 0;
    double rmse = 0, rmse_sd = 0, relmse = 0, relmse_sd = 0, relmse_min = 0, relmse_max = 0, mape = 0, mape_sd = 0,
           eff = 0, eff_sd = 0, ratio = 0;
    double relvar = 0, relvar_sd = 0, relvar_min = 0, relvar_max = 0, rv_eff = 0, rv_eff_sd = 0;
};

std::pair<double, double> mean_sd(const std::vector<double>& v) {
    double m = std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
    double s = 0;
    for (double x : v) s += (x - m) * (x - m);
    return {m, v.size() > 1 ? std::sqrt(s / double(v.size() - 1)) : 0.0};
}

std::vector<Summary> summarise(const std::vector<Sample>& samples) {
    std::map<double, std::vector<const Sample*>> by_t;
    for (const Sample& s : samples) by_t[s.target].push_back(&s);
    std::vector<Summary> out;
    for (auto& [t, v] : by_t) {
        Summary s;
        s.target = t;
        s.n = int(v.size());
        std::vector<double> time, spp, rmse, rel, mape, eff, ratio, rv, rv_eff;
        for (const Sample* x : v) {
            time.push_back(x->time_s);
            spp.push_back(double(x->spp));
            rmse.push_back(x->err.rmse);
            rel.push_back(x->err.relmse);
            mape.push_back(x->err.mape);
            eff.push_back(1.0 / (x->err.rmse * x->err.rmse * x->time_s));
            ratio.push_back(x->err.mean_ratio);
            rv.push_back(x->relvar);
            rv_eff.push_back(1.0 / (x->relvar * x->time_s));
        }
        s.time = mean_sd(time).first;
        s.spp = mean_sd(spp).first;
        std::tie(s.rmse, s.rmse_sd) = mean_sd(rmse);
        std::tie(s.relmse, s.relmse_sd) = mean_sd(rel);
        s.relmse_min = *std::min_element(rel.begin(), rel.end());
        s.relmse_max = *std::max_element(rel.begin(), rel.end());
        std::tie(s.mape, s.mape_sd) = mean_sd(mape);
        std::tie(s.eff, s.eff_sd) = mean_sd(eff);
        s.ratio = mean_sd(ratio).first;
        std::tie(s.relvar, s.relvar_sd) = mean_sd(rv);
        s.relvar_min = *std::min_element(rv.begin(), rv.end());
        s.relvar_max = *std::max_element(rv.begin(), rv.end());
        std::tie(s.rv_eff, s.rv_eff_sd) = mean_sd(rv_eff);
        out.push_back(s);
    }
    return out;
}

// "cornell-box/scene.xml" rather than a bare "scene.xml".
std::string scene_label(const std::string& path) {
    fs::path p(path);
    std::string parent = p.parent_path().filename().string();
    return parent.empty() ? p.filename().string() : parent + "/" + p.filename().string();
}

std::string gp_quote(const std::string& s) {
    std::string o = "'";
    for (char c : s) o += c == '\'' ? std::string("''") : std::string(1, c);
    return o + "'";
}

}  // namespace

void add_converge_command(CLI::App& app, ConvergeArgs& a) {
    auto* cmd = app.add_subcommand("converge", "Measure error against a reference over render time, per integrator");
    cmd->add_option("scene", a.scene, "Scene file (YAML v1 or Mitsuba XML)")->required();
    cmd->add_option("--reference", a.reference,
                    "Reference image (EXR or anything OIIO reads); an integer multiple of the film size is "
                    "filtered down with the film's filter. Without it, a long path-traced reference is rendered first");
    cmd->add_option("--integrators", a.integrators, "Comma-separated: path, bdpt, light")->delimiter(',');
    cmd->add_option("--sampler", a.sampler, "sobol | independent for the runs (overrides the scene's sampler)")
        ->check(CLI::IsMember({"sobol", "independent"}));
    cmd->add_option("--budget", a.budget_s, "Longest render, seconds (checkpoints at 1, 2, 4, ... budget)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--runs", a.runs, "Independent runs (seeds) per integrator")->check(CLI::Range(1, 1000));
    cmd->add_option("--out-dir", a.out_dir, "Where the CSVs and the plot go (default: converge-<scene name>)");
    cmd->add_option("--threads", a.threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
    cmd->add_option("--seed", a.seed, "Base seed: run r uses seed + 1 + r (the reference uses seed + 1000003)");
    cmd->add_option("--width", a.width, "Override the film width (pixels)")->check(CLI::Range(1, 65536));
    cmd->add_option("--height", a.height, "Override the film height (pixels)")->check(CLI::Range(1, 65536));
    cmd->add_option("--reference-time", a.reference_time_s, "Without --reference: seconds for the reference (default 4 x budget)")
        ->check(CLI::PositiveNumber);
    cmd->add_flag("--no-reference", a.no_reference,
                  "No reference: report each image's own estimated relative variance (mean of var / max(mean, 0.1)^2 "
                  "from the film's per-pixel variance) and fit its slope");
    cmd->add_option("-D,--define", a.defines, "Mitsuba XML scenes: set a <default> variable, name=value (repeatable)");
    cmd->add_flag("--breakdown", a.breakdown,
                  "Also measure the error per path class: a short pilot picks the classes carrying the most energy; "
                  "writes NAME_classes.csv, classes.png and which class limits convergence");
    cmd->add_option("--breakdown-classes", a.breakdown_classes, "--breakdown: how many classes (default 6)")
        ->check(CLI::Range(1, 16));
}

int run_converge(const ConvergeArgs& a) {
    MitsubaOptions xml;
    if (!parse_defines(a.defines, xml.defines)) return 2;
    if (a.no_reference && (!a.reference.empty() || a.reference_time_s)) {
        fmt::print(stderr, "omega converge: --no-reference cannot be combined with --reference or --reference-time\n");
        return 2;
    }
    const bool variance_mode = a.no_reference;
    for (const std::string& i : a.integrators)
        if (i != "path" && i != "bdpt" && i != "light") {
            fmt::print(stderr, "omega converge: unknown integrator '{}' (known: path, bdpt, light)\n", i);
            return 2;
        }
    SceneDesc desc;
    std::unique_ptr<Scene> scene;
    try {
        desc = load_scene_file(a.scene, xml);
        FilmDesc& f = desc.sensor.film;
        if ((a.width || a.height) && f.has_crop) {
            fmt::print(stderr, "omega converge: --width/--height cannot be combined with a film crop\n");
            return 2;
        }
        if (a.width) f.width = *a.width;
        if (a.height) f.height = *a.height;
        if (!f.has_crop) f.crop = {0, 0, f.width, f.height};
        scene = Scene::build(desc);
    } catch (const SceneError& e) {
        fmt::print(stderr, "omega: {}\n", e.what());
        return 2;
    }
    for (const auto& w : scene->warnings()) desc.warnings.push_back(w);
    for (const auto& w : desc.warnings) fmt::print(stderr, "omega: warning: {}\n", w);

    fs::path out_dir = a.out_dir.empty() ? fs::path("converge-" + fs::path(a.scene).stem().string()) : fs::path(a.out_dir);
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    if (ec) {
        fmt::print(stderr, "omega converge: cannot create '{}': {}\n", out_dir.string(), ec.message());
        return 2;
    }
    const FilmDesc& film = desc.sensor.film;
    const int W = film.crop[2] - film.crop[0], H = film.crop[3] - film.crop[1];

    // ---- the reference
    ImagePixels ref;
    std::string ref_note;
    if (variance_mode) {
        ref_note = "none (estimated variance)";
        fmt::print("mode: variance (no reference). Each checkpoint reports the image's own estimated relative variance, "
                   "relvar = mean over pixels and channels of var / max(mean, {})^2, from the film's per-pixel variance "
                   "(the EXR's var.* channels). It measures noise only: bias is invisible to it.\n",
                   kRelVarEps);
    } else if (!a.reference.empty()) {
        fmt::print("mode: reference (error against {})\n", a.reference);
        try {
            ref = read_rgb(a.reference);
        } catch (const std::exception& e) {
            fmt::print(stderr, "omega converge: cannot read the reference: {}\n", e.what());
            return 2;
        }
        int rw = ref.width, rh = ref.height;
        if (film.has_crop && rw == film.width && rh == film.height) {
            ref = cut(ref, film.crop[0], film.crop[1], film.crop[2], film.crop[3]);
            ref_note = fmt::format("{} (cropped to the film's crop)", a.reference);
        } else if (rw == W && rh == H) {
            ref_note = a.reference;
        } else if (rw % W == 0 && rh % H == 0 && rw / W == rh / H && !film.has_crop) {
            ref = downsample(ref, W, H, film.filter);
            ref_note = fmt::format("{} ({}-filtered down {}x from {}x{})", a.reference, filter_word(film.filter), rw / W, rw, rh);
        } else {
            fmt::print(stderr,
                       "omega converge: the reference is {}x{} but the film renders {}x{} (give --width/--height "
                       "that divide it)\n",
                       rw, rh, W, H);
            return 2;
        }
        fmt::print("reference: {}\n", ref_note);
    } else {
        double t = a.reference_time_s.value_or(4 * a.budget_s);
        RenderSettings rs;
        rs.halt.time_s = t;
        rs.threads = a.threads;
        rs.seed = a.seed + 1000003;
        rs.integrator = desc.integrator;
        rs.integrator.type = IntegratorType::Path;
        fmt::print("mode: reference (rendered: there is no --reference; --no-reference measures variance instead)\n");
        fmt::print("no --reference: rendering one with the path tracer for {:g} s (seed {}). It is independent of the "
                   "runs, so the error measures variance (and the reference's own noise), not bias.\n",
                   t, rs.seed);
        RenderSession s(*scene, rs);
        PassReport r = s.run();
        ref = film_image(s.film());
        std::string path = (out_dir / "reference.exr").string();
        ExrMeta meta;
        meta.spp = r.spp;
        meta.time_s = r.elapsed_s;
        meta.integrator = "path";
        meta.seed = rs.seed;
        meta.attributes["omega.sampler"] = sampler_name(rs.integrator.sampler);
        write_exr(path, s.film(), meta);
        ref_note = fmt::format("{} (path tracer, {} spp in {:.1f} s)", path, r.spp, r.elapsed_s);
        fmt::print("reference: {}\n", ref_note);
    }

    // ---- the classes (--breakdown): a pilot with the first integrator, then the classes as AOVs
    std::optional<ConvergeBreakdown> classes;
    if (a.breakdown) {
        IntegratorDesc id = desc.integrator;
        const std::string& first = a.integrators.front();
        id.type = first == "bdpt" ? IntegratorType::Bdpt : first == "light" ? IntegratorType::Light : IntegratorType::Path;
        if (auto s = sampler_from_name(a.sampler)) id.sampler = *s;
        const size_t room = size_t(kMaxAovs) - std::min(size_t(kMaxAovs), desc.sensor.film.aovs.size());
        try {
            classes.emplace(*scene, id, a.threads, a.seed + 2000003, std::clamp(a.budget_s / 4, 0.5, 10.0),
                            int(std::min(room, size_t(a.breakdown_classes))));
        } catch (const std::invalid_argument& e) {
            fmt::print(stderr, "omega converge: --breakdown: {}\n", e.what());
            return 2;
        }
        classes->add_aovs(desc.sensor.film);
        scene = Scene::build(desc);
    }

    // ---- the runs
    const std::vector<double> times = converge_times(a.budget_s);
    struct Result {
        std::string name;
        std::vector<Summary> summary;
        double slope = 0;
    };
    std::vector<Result> results;
    std::vector<std::string> refused;
    for (const std::string& name : a.integrators) {
        IntegratorDesc id = desc.integrator;
        id.type = name == "bdpt" ? IntegratorType::Bdpt : name == "light" ? IntegratorType::Light : IntegratorType::Path;
        if (auto s = sampler_from_name(a.sampler)) id.sampler = *s;
        fmt::print("{}: sampler {}\n", name, sampler_name(id.sampler));
        std::vector<Sample> samples;
        bool ok = true;
        for (int run = 0; run < a.runs && ok; ++run) {
            RenderSettings rs;
            rs.halt.time_s = a.budget_s;
            rs.threads = a.threads;
            rs.seed = a.seed + 1 + uint64_t(run);
            rs.integrator = id;
            std::unique_ptr<RenderSession> session;
            try {
                session = std::make_unique<RenderSession>(*scene, rs);
            } catch (const std::invalid_argument& e) {
                fmt::print(stderr, "omega converge: integrator '{}' is not available: {}; skipped, the others go on\n",
                           name, e.what());
                refused.push_back(name);
                ok = false;
                break;
            }
            size_t next = 0;
            double overhead = 0;  // snapshot time, not counted as render time
            std::vector<std::pair<Sample, ImagePixels>> snaps;
            // final: the run's last report, which stands for every checkpoint not yet reached (a
            // time halt ends the run a little before its budget by the session's own clock, and
            // on a loaded machine that last checkpoint then had no row).
            auto record = [&](const PassReport& r, bool final) {
                if (next >= times.size() || (!final && r.elapsed_s < times[next])) return;
                auto t0 = std::chrono::steady_clock::now();
                Sample s;
                s.run = run;
                s.seed = rs.seed;
                while (next < times.size() && (final || r.elapsed_s >= times[next])) s.target = times[next++];
                s.spp = r.spp;
                s.time_s = r.elapsed_s - overhead;
                if (variance_mode) s.relvar = film_relvar(session->film());
                if (classes) classes->record(*session, {name, run, rs.seed, s.target, s.time_s, s.spp, 0, {}, {}});
                snaps.emplace_back(s, variance_mode ? ImagePixels() : film_image(session->film()));
                overhead += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            };
            const PassReport fin = session->run([&](const PassReport& r) { record(r, false); });
            if (fin.pass > 0 && !session->aborted()) record(fin, true);
            for (auto& [s, img] : snaps) {
                if (!variance_mode) s.err = image_error(img, ref);
                samples.push_back(s);
            }
            const Sample& last = samples.back();
            if (variance_mode)
                fmt::print("{} run {}/{} (seed {}): {} spp in {:.2f} s, relvar {:.5g}\n", name, run + 1, a.runs, rs.seed,
                           last.spp, last.time_s, last.relvar);
            else
                fmt::print("{} run {}/{} (seed {}): {} spp in {:.2f} s, relMSE {:.5g}, RMSE {:.5g}, mean ratio {:.4f}\n",
                       name, run + 1, a.runs, rs.seed, last.spp, last.time_s, last.err.relmse, last.err.rmse,
                       last.err.mean_ratio);
            std::fflush(stdout);
        }
        if (!ok) continue;

        Result res;
        res.name = name;
        res.summary = summarise(samples);
        std::vector<double> xs, ys;
        for (const Summary& s : res.summary) xs.push_back(s.time), ys.push_back(variance_mode ? s.relvar : s.relmse);
        res.slope = loglog_slope(xs, ys);

        if (variance_mode) {
            std::ofstream runs_csv(out_dir / (name + "_runs.csv"));
            runs_csv << "run,seed,time_target_s,time_s,spp,relvar\n";
            for (const Sample& s : samples)
                runs_csv << fmt::format("{},{},{:g},{:.4f},{},{:.6g}\n", s.run, s.seed, s.target, s.time_s, s.spp, s.relvar);
            std::ofstream csv(out_dir / (name + ".csv"));
            csv << "time_target_s,runs,time_s,spp,relvar,relvar_sd,relvar_min,relvar_max,efficiency,efficiency_sd\n";
            for (const Summary& s : res.summary)
                csv << fmt::format("{:g},{},{:.4f},{:.1f},{:.6g},{:.3g},{:.6g},{:.6g},{:.6g},{:.3g}\n", s.target, s.n, s.time,
                                   s.spp, s.relvar, s.relvar_sd, s.relvar_min, s.relvar_max, s.rv_eff, s.rv_eff_sd);
            results.push_back(std::move(res));
            continue;
        }

        std::ofstream runs_csv(out_dir / (name + "_runs.csv"));
        runs_csv << "run,seed,time_target_s,time_s,spp,rmse,relmse,mape,efficiency,mean_ratio\n";
        for (const Sample& s : samples)
            runs_csv << fmt::format("{},{},{:g},{:.4f},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6f}\n", s.run, s.seed, s.target,
                                    s.time_s, s.spp, s.err.rmse, s.err.relmse, s.err.mape,
                                    1.0 / (s.err.rmse * s.err.rmse * s.time_s), s.err.mean_ratio);
        std::ofstream csv(out_dir / (name + ".csv"));
        csv << "time_target_s,runs,time_s,spp,rmse,rmse_sd,relmse,relmse_sd,relmse_min,relmse_max,mape,mape_sd,"
               "efficiency,efficiency_sd,mean_ratio\n";
        for (const Summary& s : res.summary)
            csv << fmt::format("{:g},{},{:.4f},{:.1f},{:.6g},{:.3g},{:.6g},{:.3g},{:.6g},{:.6g},{:.6g},{:.3g},{:.6g},{:.3g},{:.6f}\n",
                               s.target, s.n, s.time, s.spp, s.rmse, s.rmse_sd, s.relmse, s.relmse_sd, s.relmse_min,
                               s.relmse_max, s.mape, s.mape_sd, s.eff, s.eff_sd, s.ratio);
        results.push_back(std::move(res));
    }

    // ---- summary on stdout
    for (const Result& r : results) {
        if (variance_mode) {
            fmt::print("\n{}: estimated relvar (eps {}) vs time, mean over runs (sd), log-log slope {:.3f} (1/t would be -1)\n",
                       r.name, kRelVarEps, r.slope);
            fmt::print("  {:>8} {:>9} {:>9} {:>11} {:>10} {:>11}\n", "target_s", "time_s", "spp", "relvar", "sd", "efficiency");
            for (const Summary& s : r.summary)
                fmt::print("  {:>8g} {:>9.2f} {:>9.1f} {:>11.5g} {:>10.3g} {:>11.4g}\n", s.target, s.time, s.spp, s.relvar,
                           s.relvar_sd, s.rv_eff);
            continue;
        }
        fmt::print("\n{}: relMSE (eps {}) vs time, mean over runs (sd), log-log slope {:.3f} (1/t would be -1)\n", r.name,
                   kRelMseEps, r.slope);
        fmt::print("  {:>8} {:>9} {:>9} {:>11} {:>10} {:>10} {:>10} {:>11}\n", "target_s", "time_s", "spp", "relMSE", "sd",
                   "RMSE", "MAPE", "efficiency");
        for (const Summary& s : r.summary)
            fmt::print("  {:>8g} {:>9.2f} {:>9.1f} {:>11.5g} {:>10.3g} {:>10.4g} {:>10.4g} {:>11.4g}\n", s.target, s.time,
                       s.spp, s.relmse, s.relmse_sd, s.rmse, s.mape, s.eff);
    }

    // ---- the plot
    if (!results.empty()) {
        fs::path gp = out_dir / "convergence.gp";
        std::ofstream g(gp);
        write_gnuplot_preamble(g, "convergence.gp", "convergence.png");
        if (variance_mode)
            g << fmt::format("set ylabel 'estimated relvar  (mean of var/max(x,{})^2, log scale)'\n", kRelVarEps);
        else
            g << fmt::format("set ylabel 'relMSE  (mean of (x-r)^2/(r^2+{}), log scale)'\n", kRelMseEps);
        g << "set key top right box opaque\n";
        g << fmt::format("set title {} noenhanced\n",
                         gp_quote(fmt::format("{}: {} run(s) per integrator, reference {}", scene_label(a.scene),
                                              a.runs, fs::path(ref_note).filename().string())));
        const Result& first = results.front();
        double x0 = first.summary.front().time,
               y0 = variance_mode ? first.summary.front().relvar : first.summary.front().relmse;
        g << fmt::format("ideal(x) = {:.9g} * ({:.9g} / x)\n", y0, x0);
        g << "plot ";
        for (size_t i = 0; i < results.size(); ++i) {
            const Result& r = results[i];
            g << fmt::format("{} using {} skip 1 with yerrorlines lw 2 pt 7 title {} noenhanced, \\\n    ",
                             gp_quote(r.name + ".csv"), variance_mode ? "3:5:7:8" : "3:7:9:10",
                             gp_quote(fmt::format("{} (slope {:.2f})", r.name, r.slope)));
        }
        g << "ideal(x) with lines dt 2 lc rgb 'gray40' title 'slope -1 (ideal 1/t)'\n";
        g.close();
        run_gnuplot(out_dir, "convergence.gp", "convergence.png");
    }
    if (classes) classes->write(out_dir);
    fmt::print("CSV files: {}\n", out_dir.string());
    if (!refused.empty()) {
        std::string list;
        for (auto& r : refused) list += (list.empty() ? "" : ", ") + r;
        fmt::print(stderr, "omega converge: not measured (refused by the renderer): {}\n", list);
    }
    return results.empty() ? 2 : 0;
}

void add_compare_command(CLI::App& app, CompareArgs& a) {
    auto* cmd = app.add_subcommand("compare", "Error of an image against a reference (RMSE, relMSE, MAPE, mean ratio)");
    cmd->add_option("image", a.image, "Image to judge")->required();
    cmd->add_option("reference", a.reference, "Reference (an integer multiple of the image size is filtered down)")
        ->required();
    cmd->add_option("--filter", a.filter, "Filter for reducing the reference: the image's reconstruction filter")
        ->check(CLI::IsMember({"box", "tent", "gaussian"}));
}

int run_compare(const CompareArgs& a) {
    ImagePixels img, ref;
    try {
        img = read_rgb(a.image);
        ref = read_rgb(a.reference);
    } catch (const std::exception& e) {
        fmt::print(stderr, "omega compare: {}\n", e.what());
        return 2;
    }
    int w = img.width, h = img.height, rw = ref.width, rh = ref.height;
    if (rw != w || rh != h) {
        if (rw % w || rh % h || rw / w != rh / h) {
            fmt::print(stderr, "omega compare: sizes {}x{} and {}x{} do not match\n", w, h, rw, rh);
            return 2;
        }
        FilterType f = a.filter == "box" ? FilterType::Box : a.filter == "gaussian" ? FilterType::Gaussian : FilterType::Tent;
        ref = downsample(ref, w, h, f);
        fmt::print("reference {}-filtered down {}x\n", a.filter, rw / w);
    }
    // Each holds its data window's pixels from (0, 0): an EXR's window may start elsewhere, and
    // the two compare pixel for pixel.
    ImageError e = image_error(img, ref);
    fmt::print("RMSE {:.6g}  relMSE {:.6g} (eps {})  MAPE {:.6g}  mean ratio {:.6f}\n", e.rmse, e.relmse, kRelMseEps,
               e.mape, e.mean_ratio);
    return 0;
}

}  // namespace omega
