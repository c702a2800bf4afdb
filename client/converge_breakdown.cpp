#include "converge_breakdown.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>

#include "converge_command.h"
#include "integrator/breakdown.h"

namespace omega {

namespace fs = std::filesystem;

namespace {

double mean_luminance(const Film& film) {
    const Rect c = film.crop();
    double sum = 0;
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            const Vec3d m = film.pixel(x, y).mean;
            sum += 0.2126 * m.x + 0.7152 * m.y + 0.0722 * m.z;
        }
    return sum / double(std::max<long long>(1, c.area()));
}

std::string aov_name(size_t i) { return fmt::format("bd{}", i); }

}  // namespace

double film_relvar(const Film& film, const Film* relative_to) {
    const Film& den = relative_to ? *relative_to : film;
    const Rect c = film.crop();
    double sum = 0;
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            const PixelStats p = film.pixel(x, y);
            const Vec3d m = relative_to ? den.pixel(x, y).mean : p.mean;
            for (int ch = 0; ch < 3; ++ch) {
                const double d = std::max(std::abs(m[ch]), kRelVarEps);
                sum += p.var_of_mean[ch] / (d * d);
            }
        }
    return sum / (3.0 * double(c.area()));
}

void write_gnuplot_preamble(std::ostream& g, const std::string& script, const std::string& png) {
    g << "# gnuplot script written by omega converge; run `gnuplot " << script << "` in this folder\n";
    g << "set terminal pngcairo size 1000,700 enhanced font 'sans,12'\n";
    g << "set output '" << png << "'\n";
    g << "set datafile separator ','\nset logscale xy 10\nset format x '10^{%L}'\nset format y '10^{%L}'\n";
    g << "set grid xtics ytics mxtics mytics\nset xlabel 'render time (s, log scale)'\n";
}

void run_gnuplot(const fs::path& dir, const std::string& script, const std::string& png) {
    const std::string cmd = fmt::format("cd '{}' && gnuplot '{}' 2>&1", dir.string(), script);
    const int rc = std::system(cmd.c_str());
    if (rc == 0 && fs::exists(dir / png))
        fmt::print("\nplot: {}\n", (dir / png).string());
    else
        fmt::print(stderr,
                   "omega converge: could not run gnuplot (install it with scripts/install-deps); the plot script is {}\n",
                   (dir / script).string());
}

ConvergeBreakdown::ConvergeBreakdown(const Scene& scene, const IntegratorDesc& integrator, int threads, uint64_t seed,
                                     double seconds, int count) {
    RenderSettings rs;
    rs.halt.time_s = seconds;
    rs.threads = threads;
    rs.seed = seed;
    rs.integrator = integrator;
    rs.breakdown = BreakdownDesc{};
    RenderSession pilot(scene, rs);
    const PassReport r = pilot.run();
    const BreakdownReport rep = pilot.breakdown()->report();
    auto ranked = rep.of_kind("class");
    // "longer" is no class string an expression could name exactly: leave it out.
    std::erase_if(ranked, [](const BreakdownRow* row) { return row->length > kMaxBreakdownLength; });
    std::stable_sort(ranked.begin(), ranked.end(), [](auto* a, auto* b) { return a->fraction > b->fraction; });
    fmt::print("breakdown pilot ({} with {}, {} spp in {:.1f} s): the {} classes carrying the most energy:\n",
               integrator_name(integrator.type), sampler_name(integrator.sampler), r.spp, r.elapsed_s,
               std::min<size_t>(ranked.size(), size_t(count)));
    for (size_t i = 0; i < ranked.size() && i < size_t(count); ++i) {
        classes_.push_back(ranked[i]->name);
        pilot_fraction_.push_back(ranked[i]->fraction);
        fmt::print("  {:<20} {:7.3f}% +- {:.3f}%\n", ranked[i]->name, 100 * ranked[i]->fraction,
                   100 * ranked[i]->fraction_stderr);
    }
}

void ConvergeBreakdown::add_aovs(FilmDesc& film) const {
    for (size_t i = 0; i < classes_.size(); ++i) film.aovs.push_back({aov_name(i), classes_[i]});
}

void ConvergeBreakdown::record(const RenderSession& session, ClassCheckpoint c) {
    const Film& beauty = session.film();
    c.beauty_relvar = film_relvar(beauty);
    const double beauty_mean = mean_luminance(beauty);
    const auto& films = session.aovs()->films();
    // The chosen classes are the film's last AOVs (the scene may name its own before them).
    const size_t first = films.size() - classes_.size();
    for (size_t i = 0; i < classes_.size(); ++i) {
        const Film& f = films[first + i].film;
        c.energy.push_back(beauty_mean > 0 ? mean_luminance(f) / beauty_mean : 0.0);
        c.relvar.push_back(film_relvar(f, &beauty));
    }
    rows_.push_back(std::move(c));
}

void ConvergeBreakdown::write(const fs::path& out_dir) const {
    std::map<std::string, std::vector<const ClassCheckpoint*>> by_integrator;
    std::vector<std::string> order;
    for (const auto& r : rows_) {
        if (!by_integrator.count(r.integrator)) order.push_back(r.integrator);
        by_integrator[r.integrator].push_back(&r);
    }
    if (order.empty()) return;
    for (const std::string& name : order) {
        const auto& rows = by_integrator[name];
        // Per checkpoint and run: one line per class (long format, for spreadsheets).
        std::ofstream csv(out_dir / (name + "_classes.csv"));
        csv << "run,seed,time_target_s,time_s,spp,class,energy_fraction,relvar,error_fraction\n";
        for (const auto* r : rows)
            for (size_t i = 0; i < classes_.size(); ++i)
                csv << fmt::format("{},{},{:g},{:.4f},{},{},{:.6g},{:.6g},{:.6g}\n", r->run, r->seed, r->target, r->time_s,
                                   r->spp, classes_[i], r->energy[i], r->relvar[i],
                                   r->beauty_relvar > 0 ? r->relvar[i] / r->beauty_relvar : 0.0);
        // Means over runs per checkpoint, one column per class (wide, for the plot).
        std::map<double, std::vector<const ClassCheckpoint*>> by_target;
        for (const auto* r : rows) by_target[r->target].push_back(r);
        std::ofstream wide(out_dir / (name + "_classes_mean.csv"));
        wide << "time_target_s,time_s,all";
        for (const auto& c : classes_) wide << "," << c;
        wide << "\n";
        for (const auto& [target, rs] : by_target) {
            double t = 0, all = 0;
            std::vector<double> rv(classes_.size(), 0.0);
            for (const auto* r : rs) {
                t += r->time_s;
                all += r->beauty_relvar;
                for (size_t i = 0; i < rv.size(); ++i) rv[i] += r->relvar[i];
            }
            const double n = double(rs.size());
            wide << fmt::format("{:g},{:.4f},{:.6g}", target, t / n, all / n);
            for (double v : rv) wide << fmt::format(",{:.6g}", v / n);
            wide << "\n";
        }
        // The summary at the last checkpoint, averaged over runs: which class limits convergence.
        const auto& last = by_target.rbegin()->second;
        fmt::print("\n{}: error by path class at {:g} s (mean over {} run(s); relvar against the beauty, eps {})\n", name,
                   by_target.rbegin()->first, last.size(), kRelVarEps);
        size_t worst = 0;
        double worst_share = -1;
        for (size_t i = 0; i < classes_.size(); ++i) {
            double e = 0, rv = 0, all = 0;
            for (const auto* r : last) e += r->energy[i], rv += r->relvar[i], all += r->beauty_relvar;
            const double share = all > 0 ? rv / all : 0.0;
            fmt::print("  {:<20} energy {:7.3f}%  error {:7.3f}%  (relvar {:.4g})\n", classes_[i],
                       100 * e / double(last.size()), 100 * share, rv / double(last.size()));
            if (share > worst_share) worst_share = share, worst = i;
        }
        double e = 0;
        for (const auto* r : last) e += r->energy[worst];
        fmt::print("{}: {} holds {:.1f}% of the energy and {:.1f}% of the error\n", name, classes_[worst],
                   100 * e / double(last.size()), 100 * worst_share);
    }

    // The plot: relvar per class against time, one curve per integrator and class.
    std::ofstream g(out_dir / "classes.gp");
    write_gnuplot_preamble(g, "classes.gp", "classes.png");
    g << fmt::format("set ylabel 'relvar by path class  (mean of var_c/max(I,{})^2, log scale)'\n", kRelVarEps);
    g << "set key outside right box opaque\nset title 'error by path class' noenhanced\nplot ";
    bool first = true;
    for (const std::string& name : order)
        for (size_t col = 3; col <= classes_.size() + 3; ++col) {
            const std::string label = col == 3 ? name + ": all" : name + ": " + classes_[col - 4];
            g << (first ? "" : ", \\\n    ")
              << fmt::format("'{}_classes_mean.csv' using 2:{} skip 1 with linespoints lw 2 title '{}' noenhanced", name,
                             col, label);
            first = false;
        }
    g << "\n";
    g.close();
    run_gnuplot(out_dir, "classes.gp", "classes.png");
}

}  // namespace omega
