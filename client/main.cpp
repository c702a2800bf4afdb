// omega: the command-line client. A thin dispatcher: every command lives in omega_client.
// Exit codes: 0 ok, 1 internal error, 2 bad input, 3 daemon unreachable or refused.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <exception>

#include "batch_command.h"
#include "job_commands.h"
#include "merge_command.h"
#include "converge_command.h"
#include "import_command.h"
#include "render_command.h"
#include "submit_command.h"
#include "view_command.h"
#include "worker_command.h"

int main(int argc, char** argv) {
    CLI::App app{"omega: unbiased light transport renderer and render-daemon client"};
    app.require_subcommand(1);
    omega::RenderArgs render;
    omega::add_render_command(app, render);
    omega::client::SubmitArgs submit;
    omega::client::add_submit_command(app, submit);
    omega::client::JobCommands jobs;
    omega::client::add_job_commands(app, jobs);
    omega::client::BatchArgs batch;
    omega::client::add_batch_command(app, batch);
    omega::ImportArgs import_args;
    omega::add_import_command(app, import_args);
    omega::ConvergeArgs converge;
    omega::add_converge_command(app, converge);
    omega::CompareArgs compare;
    omega::add_compare_command(app, compare);
    omega::MergeArgs merge;
    omega::add_merge_command(app, merge);
    omega::client::ViewArgs view;
    omega::client::add_view_command(app, view);
    omega::client::WorkerArgs worker;
    omega::client::add_worker_command(app, worker);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        int rc = app.exit(e);
        return rc == 0 ? 0 : 2;
    }
    try {
        if (app.got_subcommand("render")) return omega::run_render(render);
        if (app.got_subcommand("submit")) return omega::client::run_submit(submit);
        if (app.got_subcommand("batch")) return omega::client::run_batch(batch);
        if (int rc = omega::client::run_job_command(app, jobs); rc >= 0) return rc;
        if (app.got_subcommand("import")) return omega::run_import(import_args);
        if (app.got_subcommand("converge")) return omega::run_converge(converge);
        if (app.got_subcommand("compare")) return omega::run_compare(compare);
        if (app.got_subcommand("merge")) return omega::run_merge(merge);
        if (app.got_subcommand("view")) return omega::client::run_view(view);
        if (app.got_subcommand("worker")) return omega::client::run_worker(worker);
    } catch (const std::exception& e) {
        fmt::print(stderr, "omega: internal error: {}\n", e.what());
        return 1;
    }
    return 2;
}
