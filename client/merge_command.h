#pragma once
// `omega merge PART... -o OUT`: combines partial renders (`omega render --samples A:B`) into the
// image one render of the whole range would give (film/partial_exr.h says how exactly).
#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace omega {

struct MergeArgs {
    std::vector<std::string> parts;
    std::string output;
    bool allow_gaps = false;
    bool quiet = false;
};

void add_merge_command(CLI::App& app, MergeArgs& args);
// Exit code: 0 merged, 1 the output could not be written, 2 a part is unreadable, not a part, or
// does not fit with the others (the message names the files).
int run_merge(const MergeArgs& args);

}  // namespace omega
