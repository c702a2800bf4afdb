// status, list, cancel, pause, resume, and the CLI wiring of every per-job command.
#include "job_commands.h"

#include <fmt/format.h>

#include <cstdio>
#include <map>

#include "remote_common.h"

namespace omega::client {

namespace proto = omega::protocol;

namespace {

std::string rate(double v) {
    if (v >= 1e9) return fmt::format("{:.2f}G", v / 1e9);
    if (v >= 1e6) return fmt::format("{:.2f}M", v / 1e6);
    if (v >= 1e3) return fmt::format("{:.1f}k", v / 1e3);
    return fmt::format("{:.0f}", v);
}

template <class Req>
int simple_request(const JobArgs& a, const char* done_text) {
    return guarded([&] {
        Connection c = connect_to(a.host);
        Req r{c.next_id(), *a.job};
        c.expect<proto::Ok>(c.request(proto::encode(r), r.id));
        c.close();
        std::printf("job %llu %s\n", (unsigned long long)*a.job, done_text);
        return kExitOk;
    });
}

}  // namespace

int run_status(const JobArgs& a) {
    return guarded([&] {
        Connection c = connect_to(a.host);
        if (a.job) {
            proto::Status s{c.next_id(), *a.job};
            const auto i = c.expect<proto::JobInfoReply>(c.request(proto::encode(s), s.id)).info;
            c.close();
            std::string out = format_table({
                {"job", std::to_string(i.job)},
                {"name", i.name},
                {"state", std::string(proto::to_string(i.state))},
                {"owner", i.owner},
                {"priority", std::to_string(i.priority)},
                {"halt", format_halt(i.halt)},
                {"progress", format_progress(i.progress, i.halt)},
                {"passes", std::to_string(i.progress.pass)},
                {"rate", rate(i.progress.samples_per_s) + " samples/s"},
            });
            std::fputs(out.c_str(), stdout);
            if (!i.workers.empty()) {  // a job on omega workers
                std::vector<std::vector<std::string>> rows{{"worker", "units done", "rendering", "samples/s"}};
                for (const auto& w : i.workers) {
                    std::string units;
                    for (const auto& u : w.units) units += (units.empty() ? "" : ",") + u;
                    rows.push_back({w.name, std::to_string(w.units_done), units.empty() ? "-" : units,
                                    rate(w.samples_per_s)});
                }
                std::fputs(("\n" + format_table(rows)).c_str(), stdout);
            }
            return kExitOk;
        }
        proto::List l{c.next_id()};
        const auto jobs = c.expect<proto::JobList>(c.request(proto::encode(l), l.id)).jobs;
        const auto& w = c.welcome();
        c.close();
        std::map<std::string, int> counts;
        for (const auto& j : jobs) counts[std::string(proto::to_string(j.state))]++;
        std::string states;
        for (const char* s : {"queued", "running", "paused", "done", "failed", "cancelled"})
            if (counts[s]) states += fmt::format("{}{} {}", states.empty() ? "" : ", ", counts[s], s);
        std::printf("daemon   %s\nserver   %s (protocol %u, auth %s%s)\njobs     %zu%s%s%s\n", c.address().text().c_str(),
                    w.server.c_str(), w.version, std::string(proto::to_string(w.auth)).c_str(),
                    w.user ? (", user " + *w.user).c_str() : "", jobs.size(), states.empty() ? "" : " (",
                    states.c_str(), states.empty() ? "" : ")");
        return kExitOk;
    });
}

int run_list(const JobArgs& a) {
    return guarded([&] {
        Connection c = connect_to(a.host);
        proto::List l{c.next_id()};
        const auto jobs = c.expect<proto::JobList>(c.request(proto::encode(l), l.id)).jobs;
        c.close();
        std::vector<std::vector<std::string>> rows{{"JOB", "STATE", "PRI", "OWNER", "PROGRESS", "NAME"}};
        for (const auto& j : jobs)
            rows.push_back({std::to_string(j.job), std::string(proto::to_string(j.state)), std::to_string(j.priority),
                            j.owner, format_progress(j.progress, j.halt), j.name});
        std::fputs(format_table(rows).c_str(), stdout);
        return kExitOk;
    });
}

int run_cancel(const JobArgs& a) { return simple_request<proto::Cancel>(a, "cancelled"); }
int run_pause(const JobArgs& a) { return simple_request<proto::Pause>(a, "paused"); }
int run_resume(const JobArgs& a) { return simple_request<proto::Resume>(a, "resumed"); }

void add_job_commands(CLI::App& app, JobCommands& j) {
    auto job_cmd = [&](const char* name, const char* help, JobArgs& a, bool job_required) {
        auto* cmd = app.add_subcommand(name, help);
        auto* opt = cmd->add_option("job", a.job, "Job id (as `omega submit` printed it)");
        if (job_required) opt->required();
        add_host_option(cmd, a.host);
        return cmd;
    };
    auto* watch = job_cmd("watch", "Stream a job's tiles into an EXR that stays current; exits when the job ends",
                          j.watch, true);
    watch->add_option("-o,--output", j.watch.output, "Output EXR (default: the job's name with .exr)");
    watch->add_option("--write-interval", j.watch.write_interval_s, "Seconds between rewrites of the output (default 0.5)")
        ->check(CLI::NonNegativeNumber);
    watch->add_flag("-q,--quiet", j.watch.quiet, "No progress bar");
    auto* fetch = job_cmd("fetch", "Write a job's current image once", j.fetch, true);
    fetch->add_option("-o,--output", j.fetch.output, "Output EXR (default: job-ID.exr)");
    job_cmd("status", "Show one job, or the daemon and its job counts", j.status, false);
    auto* list = app.add_subcommand("list", "List the daemon's jobs");
    add_host_option(list, j.list.host);
    job_cmd("cancel", "Cancel a job", j.cancel, true);
    job_cmd("pause", "Pause a job", j.pause, true);
    job_cmd("resume", "Resume a paused job", j.resume, true);
}

int run_job_command(const CLI::App& app, const JobCommands& j) {
    if (app.got_subcommand("watch")) return run_watch(j.watch);
    if (app.got_subcommand("fetch")) return run_fetch(j.fetch);
    if (app.got_subcommand("status")) return run_status(j.status);
    if (app.got_subcommand("list")) return run_list(j.list);
    if (app.got_subcommand("cancel")) return run_cancel(j.cancel);
    if (app.got_subcommand("pause")) return run_pause(j.pause);
    if (app.got_subcommand("resume")) return run_resume(j.resume);
    return -1;
}

}  // namespace omega::client
