#include "merge_command.h"

#include <fmt/format.h>

#include "film/partial_exr.h"
#include "integrator/breakdown.h"

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

namespace {

// The parts' breakdowns (omega render --samples A:B --breakdown): their exact sums add up to the
// breakdown of the merged range, bit for bit what one render of it reports. Parts without the
// sums, or of another region or length, cannot be combined: the output then carries none, and
// says so.
void merge_breakdowns(const std::vector<ExrMeta>& parts, const std::string& output, ExrMeta& out) {
    size_t with = 0;
    for (const ExrMeta& m : parts) with += m.attributes.count("omega.breakdown") + m.attributes.count("omega.breakdown_state");
    if (with == 0) return;
    try {
        std::optional<BreakdownState> all;
        for (const ExrMeta& m : parts) {
            auto it = m.attributes.find("omega.breakdown_state");
            if (it == m.attributes.end()) throw std::invalid_argument("a part carries no omega.breakdown_state");
            merge_breakdown_state(all, parse_breakdown_state(it->second));
        }
        out.attributes["omega.breakdown"] = breakdown_csv(make_breakdown_report(all->stats, all->region, all->max_length));
        out.attributes["omega.breakdown_state"] = breakdown_state_text(*all);
    } catch (const std::invalid_argument& e) {
        fmt::print(stderr, "omega merge: warning: the parts' path-class breakdowns are not merged ({}); {} carries none\n",
                   e.what(), output);
    }
}

}  // namespace

int run_merge(const MergeArgs& a) {
    std::vector<PartialRender> parts;
    parts.reserve(a.parts.size());
    try {
        for (const std::string& p : a.parts) parts.push_back(read_partial_exr(p));
    } catch (const std::exception& e) {
        fmt::print(stderr, "omega merge: {}\n", e.what());
        return 2;
    }
    std::vector<ExrMeta> parts_meta;
    for (const PartialRender& p : parts) parts_meta.push_back(p.meta);
    std::optional<MergeResult> merged;
    try {
        merged.emplace(merge_parts(std::move(parts), a.allow_gaps));
    } catch (const MergeRefused& e) {
        fmt::print(stderr, "omega merge: {}\n", e.what());
        return 2;
    }
    merge_breakdowns(parts_meta, a.output, merged->meta);
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
