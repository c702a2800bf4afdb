#include "merge_command.h"

#include <fmt/format.h>

#include "film/partial_exr.h"

namespace omega {

void add_merge_command(CLI::App& app, MergeArgs& a) {
    auto* cmd = app.add_subcommand(
        "merge", "Merge partial renders (omega render --samples A:B) into one image, exactly; the output is a part too");
    cmd->add_option("parts", a.parts, "Partial EXRs of the same scene, seed, integrator and film")->required();
    cmd->add_option("-o,--output", a.output, "Output EXR")->required();
    cmd->add_flag("--allow-gaps", a.allow_gaps,
                  "Merge even when sample ranges are missing between the parts (listed in omega.gaps)");
    cmd->add_flag("-q,--quiet", a.quiet, "Print nothing on success");
}

int run_merge(const MergeArgs& a) {
    std::vector<PartialRender> parts;
    parts.reserve(a.parts.size());
    try {
        for (const std::string& p : a.parts) parts.push_back(read_partial_exr(p));
    } catch (const std::exception& e) {
        fmt::print(stderr, "omega merge: {}\n", e.what());
        return 2;
    }
    // A part's breakdown (omega render --breakdown) holds its own sample range's statistics as
    // rounded text, which cannot be combined exactly: the merged image carries none, and says so.
    bool breakdown = false;
    for (const PartialRender& p : parts) breakdown = breakdown || p.meta.attributes.count("omega.breakdown") > 0;
    if (breakdown)
        fmt::print(stderr,
                   "omega merge: warning: the parts' path-class breakdowns (omega.breakdown) are not merged; {} carries "
                   "none (render the whole range with --breakdown for one)\n",
                   a.output);
    std::optional<MergeResult> merged;
    try {
        merged.emplace(merge_parts(std::move(parts), a.allow_gaps));
    } catch (const MergeRefused& e) {
        fmt::print(stderr, "omega merge: {}\n", e.what());
        return 2;
    }
    try {
        append_aov_layers(merged->aovs, merged->meta);
        write_partial_exr(a.output, merged->film, merged->meta, merged->part, merged->aovs);
    } catch (const std::exception& e) {
        fmt::print(stderr, "omega merge: {}\n", e.what());
        return 1;
    }
    if (!merged->gaps.empty())
        fmt::print(stderr, "omega merge: warning: {} holds no samples {} (omega.gaps)\n", a.output,
                   format_ranges(merged->gaps));
    if (!a.quiet)
        fmt::print("{}: {} part(s), samples {} ({} spp), rel. error {:.4f}\n", a.output, a.parts.size(),
                   format_ranges(merged->part.ranges), merged->meta.spp, merged->meta.rel_error);
    return 0;
}

}  // namespace omega
