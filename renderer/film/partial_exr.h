#pragma once
// Partial renders: sample ranges rendered apart (`omega render --samples A:B`, possibly on other
// machines) that merge back into one image (`omega merge`).
//
// A part is an ordinary EXR (R, G, B, var.*: any viewer opens it) that also carries:
// - the film's double-precision accumulator state, losslessly, in 16 UINT channels
//   (state.n.lo, state.n.hi, state.w.lo, ..., state.m2.B.hi: each 64-bit word split in two);
// - what must agree for a merge: omega.samples (the sample ranges it holds), omega.scene_hash,
//   omega.seed, omega.integrator, omega.sampler, and the display and data windows.
// A merge's output is a part as well, so merges nest (per node, then per frame).
//
// How exact: sample i of pixel p depends only on (seed, p, i), so the parts hold exactly the
// samples a single render would. The film adds them by Welford's update, which is not
// associative, and parts are combined by Chan et al.'s pairwise update (Film::merge), so the
// merged double state equals the single render's up to double rounding (relative ~1e-15). After
// conversion to float32 almost every value is bit-identical; one that straddles a float rounding
// boundary differs by 1 ulp. docs/farm.md states the promise: 1e-6 relative per pixel.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "film/aov_film.h"
#include "film/film.h"

namespace omega {

struct SampleRange {
    long long begin = 0, end = 0;  // sample indices [begin, end)
    long long size() const { return end - begin; }
};

// "A:B" with 0 <= A < B. Throws std::invalid_argument saying what is wrong.
SampleRange parse_sample_range(std::string_view text);
// "0:256,512:768" (sorted, disjoint); parse throws std::invalid_argument.
std::string format_ranges(const std::vector<SampleRange>& ranges);
std::vector<SampleRange> parse_ranges(std::string_view text);

// What a merge checks for agreement, besides the film's windows.
struct PartInfo {
    std::vector<SampleRange> ranges;  // sorted, disjoint, non-empty
    std::string scene_hash;           // scene_content_hash of the scene (client/scene_hash.h)
    uint64_t seed = 0;
    std::string integrator;
    // omega.sampler: "sobol" or "independent". Parts written before the attribute existed lack
    // it; they were made by the independent sampler and read as such.
    std::string sampler;
};

// Writes the film as a part: meta's channels and attributes plus the state channels and the
// PartInfo attributes. Throws std::runtime_error naming the path on I/O failure.
// Each AOV's state goes in 16 more channels (aov.NAME.state.*) and the list in omega.aovs, so
// AOVs merge exactly as the beauty does; their aov.NAME layers are the caller's (in meta).
void write_partial_exr(const std::string& path, const Film& film, ExrMeta meta, const PartInfo& part,
                       const std::vector<AovFilm>& aovs = {});

struct PartialRender {
    std::string path;
    PartInfo part;
    ExrMeta meta;  // spp, time_s, nonfinite, warnings, rel_error as written
    Film film;
    std::vector<AovFilm> aovs;  // from omega.aovs and the aov.NAME.state.* channels
};

// Throws std::runtime_error naming the path: unreadable, not a part (no state channels or
// omega.samples: "render it with --samples A:B"), or a state no film could hold.
PartialRender read_partial_exr(const std::string& path);

// A merge refused because of what the parts hold (not an I/O failure): the message names the
// offending files.
struct MergeRefused : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct MergeResult {
    Film film;
    ExrMeta meta;  // spp = samples held; time_s and nonfinite summed; warnings united
    PartInfo part;
    std::vector<SampleRange> gaps;  // between the first and last sample held
    std::vector<AovFilm> aovs;      // merged like the film
};

// Merges parts in order of their first sample (so the argument order does not change a bit).
// Refuses (MergeRefused) parts that differ in scene hash, seed, integrator, sampler, AOVs or film windows,
// ranges that overlap, and gaps unless allow_gaps (the result then lists them in omega.gaps).
MergeResult merge_parts(std::vector<PartialRender> parts, bool allow_gaps);

}  // namespace omega
