// omega: the command-line client. Exit codes: 0 ok, 1 internal error, 2 bad input, 3 daemon
// unreachable or refused.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <exception>

#include "render_command.h"

int main(int argc, char** argv) {
    CLI::App app{"omega: unbiased light transport renderer and render-daemon client"};
    app.require_subcommand(1);
    omega::RenderArgs render;
    omega::add_render_command(app, render);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        int rc = app.exit(e);
        return rc == 0 ? 0 : 2;
    }
    try {
        if (app.got_subcommand("render")) return omega::run_render(render);
    } catch (const std::exception& e) {
        fmt::print(stderr, "omega: internal error: {}\n", e.what());
        return 1;
    }
    return 2;
}
