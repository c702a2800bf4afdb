#pragma once
// `omega converge --breakdown`: which path class limits convergence. A short pilot render's
// breakdown (integrator/breakdown.h) picks the classes carrying the most energy; each becomes a
// light path expression output (its exact class string, e.g. `L S S D E`), whose film carries
// per-pixel variance like the beauty's. At every checkpoint of every run, per class c:
//   energy share = mean luminance of c's image / that of the beauty,
//   relvar_c     = mean over pixels and channels of var_c,p / max(I_p, eps)^2 (I: the beauty,
//                  eps = kRelVarEps: the beauty's relvar on the same scale),
//   error share  = relvar_c / relvar of the beauty.
// The classes' error shares need not sum to 1: their estimates covary (one sample feeds several).
// Concurrency: the driver thread only (converge's pass callbacks run there).
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "film/film.h"
#include "integrator/render_session.h"
#include "scene/scene.h"

namespace omega {

struct ClassCheckpoint {
    std::string integrator;
    int run = 0;
    uint64_t seed = 0;
    double target = 0, time_s = 0;
    long long spp = 0;
    double beauty_relvar = 0;
    std::vector<double> energy, relvar;  // per chosen class
};

class ConvergeBreakdown {
public:
    // Runs the pilot (the scene's integrator settings as given, `seconds` long, seed `seed`) and
    // keeps the `count` classes carrying the most energy. Prints what it chose.
    ConvergeBreakdown(const Scene& scene, const IntegratorDesc& integrator, int threads, uint64_t seed, double seconds,
                      int count);
    const std::vector<std::string>& classes() const { return classes_; }
    // Adds the chosen classes to the film as AOVs bd0, bd1, ... (the scene must then be rebuilt).
    void add_aovs(FilmDesc& film) const;
    // One checkpoint of a session whose film has add_aovs()' outputs (between passes).
    void record(const RenderSession& session, ClassCheckpoint c);
    // NAME_classes.csv per integrator, classes.gp/.png (relvar per class against time, one curve
    // per integrator and class, through gnuplot as convergence.png is), and the summary lines.
    void write(const std::filesystem::path& out_dir) const;

private:
    std::vector<std::string> classes_;
    std::vector<double> pilot_fraction_;
    std::vector<ClassCheckpoint> rows_;
};

// relvar of `film` against the means of `relative_to` (itself when null): the mean over pixels
// and channels of var / max(|mean|, kRelVarEps)^2.
double film_relvar(const Film& film, const Film* relative_to = nullptr);

// The start of a log-log plot of something against render time, written to PNG.
void write_gnuplot_preamble(std::ostream& g, const std::string& script, const std::string& png);
// Runs `gnuplot SCRIPT` in `dir`; prints where the PNG is, or how to make it by hand.
void run_gnuplot(const std::filesystem::path& dir, const std::string& script, const std::string& png);

}  // namespace omega
