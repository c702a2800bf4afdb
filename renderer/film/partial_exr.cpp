#include "film/partial_exr.h"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cstdlib>
#include <set>

#include "pathspace/lpe.h"

namespace omega {

namespace {

// The eight 64-bit words of a PixelState, in channel order.
constexpr std::array<const char*, 8> kWords = {"n", "w", "mean.R", "mean.G", "mean.B", "m2.R", "m2.G", "m2.B"};

// The beauty's state channels are state.WORD.lo/hi; an AOV's are aov.NAME.state.WORD.lo/hi.
std::string lo_name(const char* word, const std::string& prefix = {}) { return prefix + "state." + word + ".lo"; }
std::string hi_name(const char* word, const std::string& prefix = {}) { return prefix + "state." + word + ".hi"; }
std::string aov_prefix(const std::string& name) { return "aov." + name + "."; }

std::array<uint64_t, 8> words_of(const PixelState& s) {
    return {s.n,
            std::bit_cast<uint64_t>(s.w),
            std::bit_cast<uint64_t>(s.mean[0]),
            std::bit_cast<uint64_t>(s.mean[1]),
            std::bit_cast<uint64_t>(s.mean[2]),
            std::bit_cast<uint64_t>(s.m2[0]),
            std::bit_cast<uint64_t>(s.m2[1]),
            std::bit_cast<uint64_t>(s.m2[2])};
}

PixelState state_of(const std::array<uint64_t, 8>& v) {
    PixelState s;
    s.n = v[0];
    s.w = std::bit_cast<double>(v[1]);
    for (int c = 0; c < 3; ++c) {
        s.mean[c] = std::bit_cast<double>(v[2 + c]);
        s.m2[c] = std::bit_cast<double>(v[5 + c]);
    }
    return s;
}

long long parse_count(std::string_view t, std::string_view whole) {
    long long v = 0;
    auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || ec != std::errc() || p != t.data() + t.size() || v < 0)
        throw std::invalid_argument("sample range '" + std::string(whole) +
                                    "': expected A:B with whole numbers 0 <= A < B");
    return v;
}

FilmDesc film_desc_of(const ExrImage& img) {
    FilmDesc d;
    d.width = img.display_width;
    d.height = img.display_height;
    d.has_crop = img.x0 != 0 || img.y0 != 0 || img.width != img.display_width || img.height != img.display_height;
    d.crop = {img.x0, img.y0, img.x0 + img.width, img.y0 + img.height};
    return d;
}

std::string windows_text(const Film& f) {
    const Rect c = f.crop();
    return std::to_string(f.width()) + "x" + std::to_string(f.height()) + " (data window " + std::to_string(c.x0) +
           "," + std::to_string(c.y0) + " to " + std::to_string(c.x1) + "," + std::to_string(c.y1) + ")";
}

}  // namespace

SampleRange parse_sample_range(std::string_view text) {
    const size_t colon = text.find(':');
    if (colon == std::string_view::npos)
        throw std::invalid_argument("sample range '" + std::string(text) + "': expected A:B");
    SampleRange r{parse_count(text.substr(0, colon), text), parse_count(text.substr(colon + 1), text)};
    if (r.begin >= r.end)
        throw std::invalid_argument("sample range '" + std::string(text) + "' is empty: A must be below B");
    return r;
}

std::string format_ranges(const std::vector<SampleRange>& ranges) {
    std::string out;
    for (const SampleRange& r : ranges) {
        if (!out.empty()) out += ',';
        out += std::to_string(r.begin);
        out += ':';
        out += std::to_string(r.end);
    }
    return out;
}

std::vector<SampleRange> parse_ranges(std::string_view text) {
    std::vector<SampleRange> out;
    while (!text.empty()) {
        const size_t comma = text.find(',');
        out.push_back(parse_sample_range(text.substr(0, comma)));
        if (out.size() > 1 && out.back().begin < out[out.size() - 2].end)
            throw std::invalid_argument("sample ranges are not sorted and disjoint");
        if (comma == std::string_view::npos) break;
        text.remove_prefix(comma + 1);
    }
    if (out.empty()) throw std::invalid_argument("no sample range");
    return out;
}

namespace {

// The film's exact state as 16 UINT channels named with `prefix`.
void append_state_channels(const Film& film, const std::string& prefix, ExrMeta& meta) {
    const Rect c = film.crop();
    const size_t area = size_t(c.area());
    std::array<std::vector<uint32_t>, 16> planes;
    for (auto& p : planes) p.resize(area);
    size_t i = 0;
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x, ++i) {
            const auto w = words_of(film.state(x, y));
            for (size_t k = 0; k < w.size(); ++k) {
                planes[2 * k][i] = uint32_t(w[k]);
                planes[2 * k + 1][i] = uint32_t(w[k] >> 32);
            }
        }
    for (size_t k = 0; k < kWords.size(); ++k) {
        meta.uint_channels.push_back({lo_name(kWords[k], prefix), std::move(planes[2 * k])});
        meta.uint_channels.push_back({hi_name(kWords[k], prefix), std::move(planes[2 * k + 1])});
    }
}

// Restores a film's state from the channels named with `prefix`; throws std::runtime_error
// (without the path: the caller adds it) for a missing channel or a state no film could hold.
void read_state_channels(const ExrImage& img, const std::string& prefix, Film& film) {
    std::array<const std::vector<uint32_t>*, 16> planes{};
    for (size_t k = 0; k < kWords.size(); ++k) {
        for (int half = 0; half < 2; ++half) {
            const std::string name = half ? hi_name(kWords[k], prefix) : lo_name(kWords[k], prefix);
            auto it = img.uint_channels.find(name);
            if (it == img.uint_channels.end()) throw std::runtime_error("no channel " + name);
            planes[2 * k + size_t(half)] = &it->second;
        }
    }
    size_t i = 0;
    try {
        for (int y = img.y0; y < img.y0 + img.height; ++y)
            for (int x = img.x0; x < img.x0 + img.width; ++x, ++i) {
                std::array<uint64_t, 8> w{};
                for (size_t k = 0; k < w.size(); ++k)
                    w[k] = uint64_t((*planes[2 * k])[i]) | uint64_t((*planes[2 * k + 1])[i]) << 32;
                film.set_state(x, y, state_of(w));
            }
    } catch (const std::runtime_error& e) {
        throw std::runtime_error(prefix + "state channels: " + e.what());
    }
}

}  // namespace

void write_partial_exr(const std::string& path, const Film& film, ExrMeta meta, const PartInfo& part,
                       const std::vector<AovFilm>& aovs) {
    append_state_channels(film, {}, meta);
    for (const AovFilm& a : aovs) append_state_channels(a.film, aov_prefix(a.name), meta);
    if (!aovs.empty()) meta.attributes["omega.aovs"] = format_aov_list(aovs);
    meta.attributes["omega.samples"] = format_ranges(part.ranges);
    meta.attributes["omega.scene_hash"] = part.scene_hash;
    meta.seed = part.seed;
    meta.integrator = part.integrator;
    meta.attributes["omega.sampler"] = part.sampler;
    write_exr(path, film, meta);
}

PartialRender read_partial_exr(const std::string& path) {
    ExrImage img = read_exr(path);
    auto fail = [&](const std::string& why) -> std::runtime_error {
        return std::runtime_error(path + ": " + why);
    };
    const auto samples = img.attributes.find("omega.samples");
    if (samples == img.attributes.end() || !img.uint_channels.count(lo_name(kWords[0])))
        throw fail("not a partial render (no omega.samples or state.* channels): render parts with "
                   "`omega render --samples A:B`");
    PartialRender out{path, {}, {}, Film(film_desc_of(img))};
    try {
        out.part.ranges = parse_ranges(samples->second);
    } catch (const std::invalid_argument& e) {
        throw fail(std::string("omega.samples: ") + e.what());
    }
    auto attr = [&](const char* key) {
        auto it = img.attributes.find(key);
        if (it == img.attributes.end()) throw fail(std::string("no ") + key + " attribute");
        return it->second;
    };
    out.part.scene_hash = attr("omega.scene_hash");
    out.part.integrator = attr("omega.integrator");
    const auto sampler = img.attributes.find("omega.sampler");
    out.part.sampler = sampler == img.attributes.end() ? "independent" : sampler->second;
    out.meta.attributes["omega.sampler"] = out.part.sampler;
    // A part's breakdown (its own range's report and exact sums): `omega merge` adds the sums up.
    for (const char* key : {"omega.breakdown", "omega.breakdown_state"})
        if (auto it = img.attributes.find(key); it != img.attributes.end()) out.meta.attributes[key] = it->second;
    const std::string seed = attr("omega.seed");
    if (std::from_chars(seed.data(), seed.data() + seed.size(), out.part.seed).ptr != seed.data() + seed.size())
        throw fail("omega.seed is not a number");
    out.meta.seed = out.part.seed;
    out.meta.integrator = out.part.integrator;
    out.meta.time_s = std::strtod(attr("omega.time_s").c_str(), nullptr);
    out.meta.nonfinite = std::strtoull(attr("omega.nonfinite").c_str(), nullptr, 10);
    if (auto it = img.attributes.find("omega.warnings"); it != img.attributes.end() && !it->second.empty()) {
        size_t start = 0;
        for (size_t nl; (nl = it->second.find('\n', start)) != std::string::npos; start = nl + 1)
            out.meta.warnings.push_back(it->second.substr(start, nl - start));
        out.meta.warnings.push_back(it->second.substr(start));
    }

    long long samples_held = 0;
    for (const SampleRange& r : out.part.ranges) samples_held += r.size();
    out.meta.spp = samples_held;
    try {
        read_state_channels(img, {}, out.film);
        if (auto it = img.attributes.find("omega.aovs"); it != img.attributes.end())
            for (auto& [name, expr] : parse_aov_list(it->second)) {
                try {
                    validate_aov_name(name);
                } catch (const std::invalid_argument& e) {
                    throw std::runtime_error(std::string("omega.aovs: ") + e.what());
                }
                out.aovs.push_back({name, expr, Film(out.film.desc())});
                read_state_channels(img, aov_prefix(name), out.aovs.back().film);
            }
    } catch (const std::runtime_error& e) {
        throw fail(e.what());
    }
    out.meta.rel_error = out.film.estimate_error().mean_rel_error;
    return out;
}

MergeResult merge_parts(std::vector<PartialRender> parts, bool allow_gaps) {
    if (parts.empty()) throw MergeRefused("nothing to merge");
    std::stable_sort(parts.begin(), parts.end(), [](const PartialRender& a, const PartialRender& b) {
        return a.part.ranges.front().begin < b.part.ranges.front().begin;
    });
    const PartialRender& first = parts.front();
    auto differs = [&](const PartialRender& p, const char* what, const std::string& mine, const std::string& theirs) {
        return MergeRefused(p.path + ": " + what + " " + mine + " differs from " + first.path + "'s " + theirs +
                            ": parts must come from the same scene, seed, integrator, sampler and film");
    };
    for (const PartialRender& p : parts) {
        if (p.part.scene_hash != first.part.scene_hash)
            throw differs(p, "scene hash", p.part.scene_hash.substr(0, 16), first.part.scene_hash.substr(0, 16));
        if (p.part.seed != first.part.seed)
            throw differs(p, "seed", std::to_string(p.part.seed), std::to_string(first.part.seed));
        if (p.part.integrator != first.part.integrator)
            throw differs(p, "integrator", p.part.integrator, first.part.integrator);
        if (p.part.sampler != first.part.sampler)
            throw differs(p, "sampler", p.part.sampler, first.part.sampler);
        if (format_aov_list(p.aovs) != format_aov_list(first.aovs))
            throw MergeRefused(p.path + ": aovs [" + format_aov_list(p.aovs) + "] differ from " + first.path + "'s [" +
                               format_aov_list(first.aovs) + "]: parts must render the same light path expressions");
        const Rect a = p.film.crop(), b = first.film.crop();
        if (p.film.width() != first.film.width() || p.film.height() != first.film.height() || a.x0 != b.x0 ||
            a.y0 != b.y0 || a.x1 != b.x1 || a.y1 != b.y1)
            throw differs(p, "film", windows_text(p.film), windows_text(first.film));
    }

    // Every range with its file, in sample order: neighbours must neither overlap nor leave a gap.
    struct Held {
        SampleRange r;
        const std::string* path;
    };
    std::vector<Held> held;
    for (const PartialRender& p : parts)
        for (const SampleRange& r : p.part.ranges) held.push_back({r, &p.path});
    std::sort(held.begin(), held.end(), [](const Held& a, const Held& b) { return a.r.begin < b.r.begin; });
    MergeResult out{Film(first.film.desc()), {}, {}, {}};
    for (size_t i = 1; i < held.size(); ++i) {
        const Held &a = held[i - 1], &b = held[i];
        const std::string span = format_ranges({a.r}) + " (" + *a.path + ") and " + format_ranges({b.r}) + " (" +
                                 *b.path + ")";
        if (b.r.begin < a.r.end) throw MergeRefused("samples overlap: " + span + "; each sample must be in one part");
        if (b.r.begin > a.r.end) {
            if (!allow_gaps)
                throw MergeRefused("samples " + format_ranges({{a.r.end, b.r.begin}}) + " are in no part, between " +
                                   span + " (--allow-gaps merges what is there)");
            out.gaps.push_back({a.r.end, b.r.begin});
        }
    }

    for (const AovFilm& a : first.aovs) out.aovs.push_back({a.name, a.expr, Film(first.film.desc())});
    std::set<std::string> seen_warnings;
    for (const PartialRender& p : parts) {
        out.film.merge(p.film);
        for (size_t i = 0; i < out.aovs.size(); ++i) out.aovs[i].film.merge(p.aovs[i].film);
        out.meta.time_s += p.meta.time_s;
        out.meta.nonfinite += p.meta.nonfinite;
        for (const std::string& w : p.meta.warnings)
            if (seen_warnings.insert(w).second) out.meta.warnings.push_back(w);
    }
    // Adjacent ranges join, so a complete merge holds one range, as a single render would.
    for (const Held& h : held) {
        if (!out.part.ranges.empty() && out.part.ranges.back().end == h.r.begin)
            out.part.ranges.back().end = h.r.end;
        else
            out.part.ranges.push_back(h.r);
    }
    for (const SampleRange& r : out.part.ranges) out.meta.spp += r.size();
    out.part.scene_hash = first.part.scene_hash;
    out.part.seed = first.part.seed;
    out.part.integrator = first.part.integrator;
    out.part.sampler = first.part.sampler;
    out.meta.attributes["omega.sampler"] = out.part.sampler;
    out.meta.seed = out.part.seed;
    out.meta.integrator = out.part.integrator;
    out.meta.rel_error = out.film.estimate_error().mean_rel_error;
    if (!out.gaps.empty()) out.meta.attributes["omega.gaps"] = format_ranges(out.gaps);
    return out;
}

}  // namespace omega
