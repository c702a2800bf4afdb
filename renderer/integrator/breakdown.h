#pragma once
// The measurement-contribution breakdown (Veach, thesis App. 8.A): how much of a measurement
// I = mu^m(Omega) each set of paths D carries, mu^m(D) = int_D f dmu, for D = each path class
// up to a length (path_class.h) and D = all paths of length k.
//
// The measurement is the mean luminance of the pixels of a region (the crop, or a pixel box).
// One independent sample unit is one camera sample (path, bdpt: with the splats of its light
// subpath) or one light path (light: one per camera sample index and pixel). Per unit, X_c is
// the luminance class c added to the region, scaled so that E[X_c] = mu^m(c); X_T = sum_c X_c.
// Summed per class: X_c, X_c^2, X_c X_T, and the unit count N. Then
//   mu(c)  = mean X_c, standard error sd(X_c)/sqrt(N);
//   f(c)   = sum X_c / sum X_T, standard error sqrt(var(X_c - f X_T)/N) / mean X_T (delta method).
// The sums are ExactSums: the report is bit-identical for any thread count, pass split or resume.
// Units of one pixel are not identically distributed to another's (the image varies), so these
// i.i.d. errors include the spread between pixels: they are conservative.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "film/film.h"
#include "integrator/exact_sum.h"
#include "integrator/path_class.h"

namespace omega {

struct BreakdownDesc {
    int max_length = 6;       // classes and lengths above this are one "longer" row
    std::optional<Rect> box;  // pixel box [x0, x1) x [y0, y1) inside the crop; none: the crop
};

// What one unit added to the region, per class and per length (Concurrency: one per thread).
class BreakdownUnit {
public:
    void clear() { classes_.clear(); }
    void add(PathClassKey key, double x) {
        if (x == 0) return;
        for (auto& e : classes_)
            if (e.first == key) {
                e.second += x;
                return;
            }
        classes_.emplace_back(key, x);
    }
    const std::vector<std::pair<PathClassKey, double>>& classes() const { return classes_; }

private:
    std::vector<std::pair<PathClassKey, double>> classes_;  // few per unit: a linear search
};

struct BreakdownMoments {
    ExactSum x, xx, xt;  // sum X, sum X^2, sum X X_T
    void add(double v, double t) {
        x.add(v);
        xx.add(v * v);
        xt.add(v * t);
    }
    void add(const BreakdownMoments& o) {
        x.add(o.x);
        xx.add(o.xx);
        xt.add(o.xt);
    }
};

// The sums of many units. Concurrency: one per render thread, merged after the render.
class BreakdownStats {
public:
    void add_unit(const BreakdownUnit& u);
    // Units that added nothing to the region still count.
    void add_empty_unit() { ++units_; }
    void merge(const BreakdownStats& o);
    // The exact sums as text (EXR header omega.breakdown_state of a partial render), so that
    // `omega merge` combines parts' breakdowns exactly; deserialize throws std::invalid_argument.
    std::string serialize() const;
    static BreakdownStats deserialize(const std::string& text);
    uint64_t units() const { return units_; }
    const std::map<PathClassKey, BreakdownMoments>& classes() const { return classes_; }
    const std::map<int, BreakdownMoments>& lengths() const { return lengths_; }
    const BreakdownMoments& total() const { return total_; }

private:
    uint64_t units_ = 0;
    std::map<PathClassKey, BreakdownMoments> classes_;  // ordered: the report is sorted by key
    std::map<int, BreakdownMoments> lengths_;           // kMaxBreakdownLength + 1: longer
    BreakdownMoments total_;
};

struct BreakdownRow {
    std::string kind;   // "class", "length" or "total"
    std::string name;   // "L D E", "k=2", "longer", "all"
    int length = 0;     // k; kMaxBreakdownLength + 1 for the longer row; 0 for the total
    PathClassKey key = 0;
    double mu = 0, mu_stderr = 0, fraction = 0, fraction_stderr = 0;
};

struct BreakdownReport {
    std::string region;  // "image" or "box:x0:y0:x1:y1" (colons: it is a CSV field)
    int max_length = 6;
    uint64_t units = 0;
    std::vector<BreakdownRow> rows;  // the classes by length then key, the lengths, the total
    // The rows of one kind.
    std::vector<const BreakdownRow*> of_kind(const std::string& kind) const;
};

BreakdownReport make_breakdown_report(const BreakdownStats& stats, const std::string& region, int max_length);

// What a partial render carries so that its breakdown merges exactly with other parts'
// (EXR header omega.breakdown_state): the region, the length and the exact sums.
struct BreakdownState {
    std::string region;
    int max_length = 6;
    BreakdownStats stats;
};
std::string breakdown_state_text(const BreakdownState& s);
// Throws std::invalid_argument for text breakdown_state_text would not write.
BreakdownState parse_breakdown_state(const std::string& text);
// Adds part `s` to the running total `all` (empty: s becomes it). The exact sums make the result
// bit for bit one render's of the union of the parts' samples. Throws std::invalid_argument when
// the region or the length differ.
void merge_breakdown_state(std::optional<BreakdownState>& all, BreakdownState s);

// "region,kind,class,length,mu,mu_stderr,fraction,fraction_stderr" and one line per row.
std::string breakdown_csv(const BreakdownReport& r);
// A short table for a terminal: the classes and lengths carrying at least `min_fraction`.
std::string breakdown_table(const BreakdownReport& r, double min_fraction = 0.001);
// Reads breakdown_csv's text back (for tests and `omega converge`). Throws std::invalid_argument.
BreakdownReport parse_breakdown_csv(const std::string& text);

}  // namespace omega
