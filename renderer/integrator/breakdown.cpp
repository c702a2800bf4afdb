#include "integrator/breakdown.h"

#include <fmt/format.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace omega {

std::string ExactSum::text() const {
    if (overflow_) return "nan";
    const auto d = digits();
    int lo = 0, hi = kLimbs - 1;
    while (lo < kLimbs && d[size_t(lo)] == 0) ++lo;
    if (lo == kLimbs) return "0";
    while (d[size_t(hi)] == 0) --hi;
    std::string s = fmt::format("{}:", lo);
    for (int i = lo; i <= hi; ++i) s += fmt::format("{}{:x}", i > lo ? "," : "", d[size_t(i)]);
    return s;
}

void ExactSum::set_text(std::string_view t) {
    std::array<int64_t, kLimbs> d{};
    if (t == "nan") return set_digits(d, true);
    if (t != "0") {
        const size_t colon = t.find(':');
        if (colon == std::string_view::npos) throw std::invalid_argument("exact sum: no ':'");
        int i = 0;
        try {
            i = std::stoi(std::string(t.substr(0, colon)));
            std::string rest(t.substr(colon + 1));
            std::istringstream in(rest);
            for (std::string f; std::getline(in, f, ','); ++i) {
                if (i < 0 || i >= kLimbs) throw std::invalid_argument("exact sum: limb out of range");
                size_t used = 0;
                d[size_t(i)] = std::stoll(f, &used, 16);
                if (used != f.size()) throw std::invalid_argument("exact sum: bad digit");
            }
        } catch (const std::invalid_argument&) {
            throw;
        } catch (const std::exception&) {
            throw std::invalid_argument("exact sum: bad number");
        }
    }
    set_digits(d, false);
}

std::string path_class_name(PathClassKey key) {
    if (key == kLongerClass) return "longer";
    const int k = path_class_length(key);
    std::string s(size_t(2 * k + 1), ' ');
    s[0] = 'L';
    // Light first: inner vertex x_i is vertex j = k - i from the eye.
    for (int i = 1; i < k; ++i) s[size_t(2 * i)] = (key >> (k - i - 1)) & 1 ? 'S' : 'D';
    s[size_t(2 * k)] = 'E';
    return s;
}

PathClassKey path_class_key(const std::vector<VertexClass>& signature, int max_length, int mirror_after) {
    const int k = int(signature.size()) - 1 + (mirror_after >= 0 ? 1 : 0);
    if (k > max_length) return kLongerClass;
    // Light-first position i (with the mirror vertex inserted) is eye-first inner vertex k - i.
    uint64_t bits = 0;
    int i = 0;
    for (size_t n = 0; n < signature.size(); ++n, ++i) {
        if (n > 0 && n + 1 < signature.size() && signature[n] == VertexClass::S) bits |= uint64_t(1) << (k - i - 1);
        if (int(n) == mirror_after) {
            ++i;
            bits |= uint64_t(1) << (k - i - 1);
        }
    }
    return path_class_key(k, bits, max_length);
}

void BreakdownStats::add_unit(const BreakdownUnit& u) {
    ++units_;
    double t = 0;
    for (const auto& [key, x] : u.classes()) t += x;
    if (t == 0 && u.classes().empty()) return;
    // Per length: the unit's classes of that length summed (few classes: a small local list).
    std::pair<int, double> by_length[kMaxBreakdownLength + 2];
    int n_lengths = 0;
    for (const auto& [key, x] : u.classes()) {
        classes_[key].add(x, t);
        const int k = path_class_length(key);
        int j = 0;
        while (j < n_lengths && by_length[j].first != k) ++j;
        if (j == n_lengths) by_length[n_lengths++] = {k, 0.0};
        by_length[j].second += x;
    }
    for (int j = 0; j < n_lengths; ++j) lengths_[by_length[j].first].add(by_length[j].second, t);
    total_.add(t, t);
}

void BreakdownStats::merge(const BreakdownStats& o) {
    units_ += o.units_;
    for (const auto& [k, m] : o.classes_) classes_[k].add(m);
    for (const auto& [k, m] : o.lengths_) lengths_[k].add(m);
    total_.add(o.total_);
}

namespace {

std::string moments_text(const BreakdownMoments& m) { return m.x.text() + " " + m.xx.text() + " " + m.xt.text(); }

BreakdownMoments moments_of(std::istringstream& in) {
    BreakdownMoments m;
    std::string a, b, c;
    if (!(in >> a >> b >> c)) throw std::invalid_argument("breakdown state: a truncated line");
    m.x.set_text(a);
    m.xx.set_text(b);
    m.xt.set_text(c);
    return m;
}

}  // namespace

std::string BreakdownStats::serialize() const {
    std::string s = fmt::format("units {}\n", units_);
    for (const auto& [k, m] : classes_) s += fmt::format("c {:x} {}\n", k, moments_text(m));
    for (const auto& [k, m] : lengths_) s += fmt::format("l {} {}\n", k, moments_text(m));
    return s + "t " + moments_text(total_) + "\n";
}

BreakdownStats BreakdownStats::deserialize(const std::string& text) {
    BreakdownStats st;
    std::istringstream lines(text);
    std::string line;
    bool total = false;
    while (std::getline(lines, line)) {
        std::istringstream in(line);
        std::string tag;
        in >> tag;
        if (tag == "units") {
            if (!(in >> st.units_)) throw std::invalid_argument("breakdown state: bad unit count");
        } else if (tag == "c") {
            std::string key;
            in >> key;
            try {
                st.classes_[std::stoull(key, nullptr, 16)] = moments_of(in);
            } catch (const std::out_of_range&) {
                throw std::invalid_argument("breakdown state: bad class key");
            }
        } else if (tag == "l") {
            int k = 0;
            if (!(in >> k) || k < 1 || k > kMaxBreakdownLength + 1) throw std::invalid_argument("breakdown state: bad length");
            st.lengths_[k] = moments_of(in);
        } else if (tag == "t") {
            st.total_ = moments_of(in);
            total = true;
        } else if (!tag.empty()) {
            throw std::invalid_argument("breakdown state: unknown line '" + tag + "'");
        }
    }
    if (!total) throw std::invalid_argument("breakdown state: no total");
    return st;
}

std::string breakdown_state_text(const BreakdownState& s) {
    return fmt::format("region {} {}\n", s.region, s.max_length) + s.stats.serialize();
}

BreakdownState parse_breakdown_state(const std::string& text) {
    BreakdownState s;
    const size_t nl = text.find('\n');
    std::istringstream head(text.substr(0, nl));
    std::string tag;
    if (!(head >> tag >> s.region >> s.max_length) || tag != "region" || s.max_length < 1 ||
        s.max_length > kMaxBreakdownLength)
        throw std::invalid_argument("breakdown state: no region line");
    s.stats = BreakdownStats::deserialize(nl == std::string::npos ? std::string() : text.substr(nl + 1));
    return s;
}

std::vector<const BreakdownRow*> BreakdownReport::of_kind(const std::string& kind) const {
    std::vector<const BreakdownRow*> out;
    for (const auto& r : rows)
        if (r.kind == kind) out.push_back(&r);
    return out;
}

namespace {

BreakdownRow make_row(const BreakdownMoments& m, const BreakdownMoments& total, double n) {
    BreakdownRow r;
    const double sx = m.x.value(), sxx = m.xx.value(), sxt = m.xt.value();
    const double st = total.x.value(), stt = total.xx.value();
    r.mu = sx / n;
    const double var_x = n > 1 ? std::max(0.0, (sxx - sx * sx / n) / (n - 1)) : 0.0;
    r.mu_stderr = std::sqrt(var_x / n);
    if (st != 0) {
        const double f = sx / st;
        r.fraction = f;
        // var(X - f T), whose mean is 0 by the choice of f.
        const double var_d = n > 1 ? std::max(0.0, (sxx - 2 * f * sxt + f * f * stt) / (n - 1)) : 0.0;
        r.fraction_stderr = std::sqrt(var_d / n) / (st / n);
    }
    return r;
}

}  // namespace

BreakdownReport make_breakdown_report(const BreakdownStats& stats, const std::string& region, int max_length) {
    BreakdownReport rep;
    rep.region = region;
    rep.max_length = max_length;
    rep.units = stats.units();
    const double n = double(std::max<uint64_t>(1, stats.units()));
    // The classes by length, then key (std::map order: length is the key's top bits).
    for (const auto& [key, m] : stats.classes()) {
        BreakdownRow r = make_row(m, stats.total(), n);
        r.kind = "class";
        r.key = key;
        r.name = path_class_name(key);
        r.length = path_class_length(key);
        rep.rows.push_back(r);
    }
    for (const auto& [k, m] : stats.lengths()) {
        BreakdownRow r = make_row(m, stats.total(), n);
        r.kind = "length";
        r.length = k;
        r.name = k > kMaxBreakdownLength ? "longer" : fmt::format("k={}", k);
        rep.rows.push_back(r);
    }
    BreakdownRow t = make_row(stats.total(), stats.total(), n);
    t.kind = "total";
    t.name = "all";
    rep.rows.push_back(t);
    return rep;
}

std::string breakdown_csv(const BreakdownReport& r) {
    std::string s = "region,kind,class,length,mu,mu_stderr,fraction,fraction_stderr\n";
    for (const auto& row : r.rows)
        s += fmt::format("{},{},{},{},{:.9g},{:.6g},{:.9g},{:.6g}\n", r.region, row.kind, row.name,
                         row.length > kMaxBreakdownLength ? fmt::format(">{}", r.max_length) : fmt::format("{}", row.length),
                         row.mu, row.mu_stderr, row.fraction, row.fraction_stderr);
    return s;
}

std::string breakdown_table(const BreakdownReport& r, double min_fraction) {
    std::string s = fmt::format("breakdown of {} ({} units; classes up to length {}):\n", r.region, r.units, r.max_length);
    s += fmt::format("  {:<24} {:>12} {:>10} {:>9} {:>8}\n", "paths", "mu", "+-", "fraction", "+-");
    for (const auto& row : r.rows) {
        if (row.kind != "total" && std::abs(row.fraction) < min_fraction) continue;
        const std::string name = row.kind == "class" ? row.name : "[" + row.name + "]";
        s += fmt::format("  {:<24} {:>12.6g} {:>10.3g} {:>8.4f}% {:>7.4f}%\n", name, row.mu, row.mu_stderr,
                         100 * row.fraction, 100 * row.fraction_stderr);
    }
    return s;
}

BreakdownReport parse_breakdown_csv(const std::string& text) {
    BreakdownReport r;
    std::istringstream in(text);
    std::string line;
    if (!std::getline(in, line) || line.rfind("region,kind,class,length", 0) != 0)
        throw std::invalid_argument("breakdown: not a breakdown CSV (header)");
    while (std::getline(in, line)) {
        if (line.empty()) continue;
        std::vector<std::string> f;
        std::istringstream ls(line);
        for (std::string c; std::getline(ls, c, ',');) f.push_back(c);
        if (f.size() != 8) throw std::invalid_argument("breakdown: a line without 8 fields: " + line);
        BreakdownRow row;
        r.region = f[0];
        row.kind = f[1];
        row.name = f[2];
        try {
            row.length = f[3].starts_with(">") ? kMaxBreakdownLength + 1 : std::stoi(f[3]);
            row.mu = std::stod(f[4]);
            row.mu_stderr = std::stod(f[5]);
            row.fraction = std::stod(f[6]);
            row.fraction_stderr = std::stod(f[7]);
        } catch (const std::exception&) {
            throw std::invalid_argument("breakdown: a bad number in: " + line);
        }
        r.rows.push_back(row);
    }
    return r;
}

void merge_breakdown_state(std::optional<BreakdownState>& all, BreakdownState s) {
    if (!all) {
        all = std::move(s);
        return;
    }
    if (s.region != all->region || s.max_length != all->max_length)
        throw std::invalid_argument("the parts' breakdowns differ in region or length (" + s.region + ", " +
                                    std::to_string(s.max_length) + " against " + all->region + ", " +
                                    std::to_string(all->max_length) + ")");
    all->stats.merge(s.stats);
}

}  // namespace omega
