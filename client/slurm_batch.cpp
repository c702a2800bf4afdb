#include "slurm_batch.h"

#include <fmt/format.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include "remote_common.h"
#include "scene/scene_error.h"
#include "scene/scene_parser.h"

namespace omega::client::slurm {

namespace fs = std::filesystem;

// ---------------------------------------------------------------- plans and scripts

std::vector<Chunk> split_samples(uint64_t spp, int chunks) {
    const uint64_t n = std::min<uint64_t>(spp, uint64_t(std::max(chunks, 1)));
    std::vector<Chunk> out;
    uint64_t at = 0;
    for (uint64_t i = 0; i < n; ++i) {
        const uint64_t size = spp / n + (i < spp % n ? 1 : 0);
        out.push_back({at, at + size});
        at += size;
    }
    return out;
}

namespace {

// Labels go into script comments: a newline in one must not end the comment.
std::string one_line(std::string s) {
    for (char& c : s)
        if (c == '\n' || c == '\r') c = ' ';
    return s;
}

// The last non-empty line of a job's log (omega's own "omega: ..." error), or "".
std::string last_log_line(const std::string& path) {
    std::ifstream in(path);
    std::string line, last;
    while (std::getline(in, line))
        if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
    return last;
}

std::string join(const std::vector<std::string>& v, const std::string& sep) {
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? sep : "") + v[i];
    return s;
}

}  // namespace

FramePlan plan_frame(const BatchManifest& m, size_t index, uint64_t spp, const std::string& omega_bin) {
    const BatchEntry& e = m.jobs[index];
    const SlurmSettings& s = m.slurm;
    FramePlan f;
    f.entry = &e;
    f.spp = spp;
    f.chunks = split_samples(spp, s.chunks);
    f.scene = fs::absolute(e.scene).lexically_normal().string();
    f.output = fs::absolute(e.output).lexically_normal().string();
    f.omega = s.omega.value_or(omega_bin);
    const fs::path root = s.work_dir ? fs::path(*s.work_dir) : fs::absolute(fs::path(m.output_dir) / ".omega-slurm");
    const fs::path work = root / fmt::format("{:04}-{}", index + 1, fs::path(e.output).stem().string());
    f.work = work.lexically_normal().string();
    f.render_script = (work / "render.sh").string();
    f.merge_script = (work / "merge.sh").string();
    for (size_t k = 0; k < f.chunks.size(); ++k) f.parts.push_back((work / fmt::format("part_{}.exr", k)).string());

    std::string r = fmt::format(
        "#!/bin/bash\n"
        "# omega batch --slurm: {} ({}), {} spp in {} chunk(s).\n"
        "# One task of the job array renders one chunk; SLURM_ARRAY_TASK_ID picks it, so a resubmitted\n"
        "# task (sbatch --array=K) renders the same samples into the same part.\n"
        "set -euo pipefail\n"
        "case \"${{SLURM_ARRAY_TASK_ID:?not started as a Slurm array task}}\" in\n",
        one_line(e.label), one_line(e.where), spp, f.chunks.size());
    for (size_t k = 0; k < f.chunks.size(); ++k)
        r += fmt::format("  {}) samples={}:{} part={} ;;\n", k, f.chunks[k].begin, f.chunks[k].end, sh_quote(f.parts[k]));
    r += "  *) echo \"omega batch: no chunk $SLURM_ARRAY_TASK_ID\" >&2; exit 2 ;;\nesac\n";
    std::vector<std::string> cmd{sh_quote(f.omega), "render", sh_quote(f.scene), "--samples", "\"$samples\"",
                                 "-o", "\"$part\"", "--seed", std::to_string(e.spec.seed),
                                 "--threads", std::to_string(s.cpus_per_task)};
    if (e.spec.integrator) cmd.insert(cmd.end(), {"--integrator", sh_quote(*e.spec.integrator)});
    r += "exec " + join(cmd, " ") + "\n";
    f.render_text = std::move(r);

    std::vector<std::string> merge{sh_quote(f.omega), "merge"};
    for (const auto& p : f.parts) merge.push_back(sh_quote(p));
    merge.insert(merge.end(), {"-o", sh_quote(f.output)});
    f.merge_text = fmt::format(
        "#!/bin/bash\n"
        "# omega batch --slurm: merges the {} part(s) of {} ({}) into its output. Submitted afterok of\n"
        "# every chunk; omega merge itself refuses a missing, overlapping or foreign part.\n"
        "set -euo pipefail\n"
        "exec {}\n",
        f.parts.size(), one_line(e.label), one_line(e.where), join(merge, " "));
    return f;
}

namespace {

std::vector<std::string> common_args(const SlurmSettings& s, const FramePlan& f, const std::string& name) {
    std::vector<std::string> a{"--parsable", "--job-name=" + name, "--ntasks=1", "--chdir=" + f.work};
    if (s.partition) a.push_back("--partition=" + *s.partition);
    if (s.time_limit) a.push_back("--time=" + *s.time_limit);
    return a;
}

}  // namespace

std::vector<std::string> render_sbatch_args(const SlurmSettings& s, const FramePlan& f, const std::string& tasks) {
    auto a = common_args(s, f, "omega-render-" + fs::path(f.output).stem().string());
    a.push_back("--array=" + tasks);
    a.push_back(fmt::format("--cpus-per-task={}", s.cpus_per_task));
    a.push_back("--output=" + f.work + "/render_%A_%a.log");
    a.insert(a.end(), s.sbatch_args.begin(), s.sbatch_args.end());
    a.push_back(f.render_script);
    return a;
}

std::vector<std::string> merge_sbatch_args(const SlurmSettings& s, const FramePlan& f, const std::string& dependency) {
    auto a = common_args(s, f, "omega-merge-" + fs::path(f.output).stem().string());
    a.push_back("--cpus-per-task=1");
    a.push_back("--output=" + f.work + "/merge_%j.log");
    if (!dependency.empty()) {
        a.push_back("--dependency=" + dependency);
        // A chunk that fails makes afterok unsatisfiable: Slurm then cancels the merge instead of
        // leaving it pending forever (also when this client is gone).
        a.push_back("--kill-on-invalid-dep=yes");
    }
    a.insert(a.end(), s.sbatch_args.begin(), s.sbatch_args.end());
    a.push_back(f.merge_script);
    return a;
}

// ---------------------------------------------------------------- processes

ProcResult run_process(const std::vector<std::string>& argv) {
    try {
        return run_captured(argv);
    } catch (const ProcessSpawnError& e) {
        throw ClientError(kExitUnreachable, e.what());
    } catch (const std::runtime_error& e) {
        throw ClientError(kExitInternal, e.what());
    }
}

// ---------------------------------------------------------------- reading Slurm's state

std::vector<JobRecord> parse_scontrol(const std::string& out) {
    std::vector<JobRecord> recs;
    std::istringstream lines(out);
    for (std::string line; std::getline(lines, line);) {
        if (line.rfind("JobId=", 0) != 0) continue;
        JobRecord r;
        std::istringstream words(line);
        for (std::string w; words >> w;) {
            const auto eq = w.find('=');
            if (eq == std::string::npos) continue;
            const std::string k = w.substr(0, eq), v = w.substr(eq + 1);
            if (k == "JobId") r.job_id = v;
            else if (k == "ArrayJobId") r.array_job_id = v;
            else if (k == "ArrayTaskId") r.array_tasks = v;
            else if (k == "JobState") r.state = v;
            else if (k == "Reason") r.reason = v;
            else if (k == "ExitCode") r.exit_code = v;
        }
        recs.push_back(std::move(r));
    }
    return recs;
}

bool task_in_range(const std::string& spec, int k) {
    const std::string body = spec.substr(0, spec.find('%'));  // "%4": a limit on running tasks
    std::istringstream parts(body);
    for (std::string p; std::getline(parts, p, ',');) {
        int a = 0, b = 0, step = 1;
        if (std::sscanf(p.c_str(), "%d-%d:%d", &a, &b, &step) == 3 || std::sscanf(p.c_str(), "%d-%d", &a, &b) == 2) {
            if (k >= a && k <= b && step > 0 && (k - a) % step == 0) return true;
        } else if (std::sscanf(p.c_str(), "%d", &a) == 1 && a == k) {
            return true;
        }
    }
    return false;
}

std::map<std::string, std::string> parse_squeue(const std::string& out) {
    std::map<std::string, std::string> m;
    std::istringstream lines(out);
    for (std::string id, state; lines >> id >> state;) m[id] = state;
    return m;
}

// ---------------------------------------------------------------- running

namespace {

constexpr int kMaxFailedPolls = 30;  // consecutive squeue failures before giving up on the controller

struct ChunkState {
    std::string owner;  // the array job id whose task K renders this chunk now
    int attempts = 1;
    bool done = false;
};

struct Frame {
    FramePlan plan;
    std::vector<ChunkState> chunks;
    std::string array;  // the first array's id (the summary's JOB)
    std::string merge;  // the current merge job
    int merge_failures = 0;  // of the merge job itself (not merges cancelled for a resubmitted chunk)
    bool finished = false;
    std::chrono::steady_clock::time_point start;
};

// What Slurm knows about one job or array, read once per poll.
struct Lookup {
    bool known = false;  // scontrol has the job
    bool failed = false;  // scontrol itself failed (not "no such job"): look again next poll
    std::vector<JobRecord> records;
};

class SlurmRunner {
public:
    SlurmRunner(const BatchManifest& m, std::vector<Frame> frames, std::FILE* log)
        : m_(m), frames_(std::move(frames)), log_(log), retries_(m.slurm.retries.value_or(m.retries)) {
        results_.resize(frames_.size());
        for (size_t i = 0; i < frames_.size(); ++i) results_[i].entry = frames_[i].plan.entry;
        const ProcResult probe = try_run({"sacct", "-n", "-X", "-j", "1", "-o", "JobID"});
        // Only a site with accounting answers sacct; the test cluster says "accounting storage is disabled".
        have_sacct_ = probe.status == 0 && (probe.out + probe.err).find("disabled") == std::string::npos;
    }

    std::vector<BatchResult> run() {
        for (size_t i = 0; i < frames_.size(); ++i) submit_frame(i);
        int failed_polls = 0;
        while (std::any_of(frames_.begin(), frames_.end(), [](const Frame& f) { return !f.finished; })) {
            std::this_thread::sleep_for(std::chrono::duration<double>(m_.slurm.poll_interval_s));
            if (poll()) {
                failed_polls = 0;
            } else if (++failed_polls >= kMaxFailedPolls) {
                for (size_t i = 0; i < frames_.size(); ++i)
                    if (!frames_[i].finished)
                        fail(i, kExitUnreachable, fmt::format("squeue failed {} times in a row: {}", failed_polls, last_error_));
            }
        }
        return std::move(results_);
    }

private:
    template <class... A>
    void say(size_t i, fmt::format_string<A...> f, A&&... a) {
        if (!log_) return;
        fmt::print(log_, "[{}/{}] {}: {}\n", i + 1, frames_.size(), frames_[i].plan.entry->label,
                   fmt::format(f, std::forward<A>(a)...));
        std::fflush(log_);
    }

    static ProcResult try_run(const std::vector<std::string>& argv) {
        try {
            return run_process(argv);
        } catch (const ClientError& e) {
            return ProcResult{127, "", e.what()};
        }
    }

    // Returns the new job id. Throws ClientError (exit 3) when sbatch refuses or cannot run.
    static std::string sbatch(const std::vector<std::string>& args) {
        std::vector<std::string> argv{"sbatch"};
        argv.insert(argv.end(), args.begin(), args.end());
        const ProcResult r = run_process(argv);
        std::string id = r.out.substr(0, r.out.find_first_of(";\n"));  // --parsable: "id" or "id;cluster"
        if (r.status != 0 || id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
            throw ClientError(kExitUnreachable, fmt::format("sbatch failed (status {}): {}", r.status,
                                                            one_line(r.err.empty() ? r.out : r.err)));
        return id;
    }

    static void scancel(const std::string& id) { try_run({"scancel", id}); }

    // afterok of every chunk not yet known to be done, each by its current owner task.
    std::string merge_dependency(const Frame& f) const {
        std::vector<std::string> deps;
        for (size_t k = 0; k < f.chunks.size(); ++k)
            if (!f.chunks[k].done) deps.push_back(fmt::format("{}_{}", f.chunks[k].owner, k));
        return deps.empty() ? "" : "afterok:" + join(deps, ":");
    }

    void submit_merge(size_t i, const std::string& dependency) {
        Frame& f = frames_[i];
        f.merge = sbatch(merge_sbatch_args(m_.slurm, f.plan, dependency));
        say(i, "merge job {}{}", f.merge, dependency.empty() ? "" : " (" + dependency + ")");
    }

    void write_file(const std::string& path, const std::string& text, fs::perms perms) {
        std::ofstream o(path, std::ios::binary | std::ios::trunc);
        o << text;
        o.close();
        if (!o) throw ClientError(kExitInternal, fmt::format("cannot write {}", path));
        fs::permissions(path, perms);
    }

    void submit_frame(size_t i) {
        Frame& f = frames_[i];
        f.start = std::chrono::steady_clock::now();
        results_[i].attempts = 1;
        try {
            std::error_code ec;
            fs::create_directories(f.plan.work, ec);
            const fs::path out_parent = fs::path(f.plan.output).parent_path();
            if (!out_parent.empty()) fs::create_directories(out_parent, ec);
            // A part left by an earlier run must never stand in for one of this run.
            for (const auto& p : f.plan.parts) fs::remove(p, ec);
            const auto rx = fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec;
            write_file(f.plan.render_script, f.plan.render_text, rx);
            write_file(f.plan.merge_script, f.plan.merge_text, rx);
            f.array = sbatch(render_sbatch_args(m_.slurm, f.plan, fmt::format("0-{}", f.chunks.size() - 1)));
            for (auto& c : f.chunks) c.owner = f.array;
            results_[i].job = std::stoull(f.array);
            say(i, "job array {}: {} spp in {} chunk(s)", f.array, f.plan.spp, f.chunks.size());
            submit_merge(i, "afterok:" + f.array);
        } catch (const ClientError& e) {
            if (!f.array.empty()) scancel(f.array);
            fail(i, e.exit_code(), e.what());
        }
    }

    void fail(size_t i, int code, const std::string& why) {
        Frame& f = frames_[i];
        BatchResult& r = results_[i];
        // The rest of this frame's work is of no use any more: free the cluster.
        for (const auto& c : f.chunks)
            if (!c.done && !c.owner.empty()) scancel(c.owner);
        if (!f.merge.empty()) scancel(f.merge);
        f.finished = true;
        r.state = "failed";
        r.exit_code = code;
        r.message = why;
        say(i, "failed: {}", why);
    }

    const Lookup& lookup(const std::string& id) {
        auto it = cache_.find(id);
        if (it != cache_.end()) return it->second;
        Lookup l;
        const ProcResult r = try_run({"scontrol", "-o", "show", "job", id});
        if (r.status == 0) {
            l.known = true;
            l.records = parse_scontrol(r.out);
        } else if (r.err.find("Invalid job id") == std::string::npos && r.err.find("not found") == std::string::npos) {
            l.failed = true;
        }
        return cache_.emplace(id, std::move(l)).first->second;
    }

    // The final (or current) state of task `task` of array `id` (task < 0: a plain job), once it
    // has left squeue. Empty when it is still pending or running.
    std::string final_state(const std::string& id, int task, const std::string& part) {
        const Lookup& l = lookup(id);
        if (l.failed) return "";
        if (l.known) {
            for (const auto& r : l.records) {
                const bool match = task < 0 ? r.job_id == id
                                            : r.array_job_id == id && !r.array_tasks.empty() &&
                                                  r.array_tasks.find_first_not_of("0123456789") == std::string::npos &&
                                                  std::stoi(r.array_tasks) == task;
                if (match)
                    return r.state == "COMPLETED" ? r.state
                                                  : r.state + (r.exit_code.empty() ? "" : " exit " + r.exit_code) +
                                                        (r.reason.empty() || r.reason == "None" ? "" : " " + r.reason);
                if (task >= 0 && r.array_job_id == id && task_in_range(r.array_tasks, task)) return "";  // not started
            }
            // An array task cancelled before it started leaves no record of its own.
            return "CANCELLED (before it started)";
        }
        if (have_sacct_) {
            const std::string jid = task < 0 ? id : fmt::format("{}_{}", id, task);
            const ProcResult r = try_run({"sacct", "-n", "-P", "-X", "-j", jid, "-o", "State,ExitCode"});
            if (r.status == 0 && !r.out.empty()) {
                const std::string line = r.out.substr(0, r.out.find('\n'));
                const std::string state = line.substr(0, line.find('|'));
                return state == "COMPLETED" ? state : one_line(line);
            }
        }
        // Forgotten by the controller (MinJobAge passed between two polls) and no accounting:
        // the part file is the only witness left.
        if (!part.empty() && fs::exists(part)) return "COMPLETED";
        return "UNKNOWN (no longer known to scontrol, no accounting)";
    }

    // Returns false when squeue could not be read.
    bool poll() {
        cache_.clear();
        std::set<std::string> ids;
        for (const auto& f : frames_) {
            if (f.finished) continue;
            for (const auto& c : f.chunks)
                if (!c.done) ids.insert(c.owner);
            if (!f.merge.empty()) ids.insert(f.merge);
        }
        if (ids.empty()) return true;
        const ProcResult q = try_run({"squeue", "-h", "-r", "-j", join({ids.begin(), ids.end()}, ","), "-o", "%i %T"});
        // squeue exits 1 when it knows none of the ids (all finished): that is an empty queue.
        if (q.status != 0 && q.err.find("Invalid job id") == std::string::npos) {
            last_error_ = one_line(q.err);
            return false;
        }
        const auto queued = parse_squeue(q.status == 0 ? q.out : "");
        for (size_t i = 0; i < frames_.size(); ++i)
            if (!frames_[i].finished) poll_frame(i, queued);
        return true;
    }

    void poll_frame(size_t i, const std::map<std::string, std::string>& queued) {
        Frame& f = frames_[i];
        BatchResult& r = results_[i];
        std::vector<std::pair<size_t, std::string>> failed;
        for (size_t k = 0; k < f.chunks.size(); ++k) {
            ChunkState& c = f.chunks[k];
            if (c.done || queued.count(fmt::format("{}_{}", c.owner, k))) continue;
            const std::string st = final_state(c.owner, int(k), f.plan.parts[k]);
            if (st.empty()) continue;
            if (st == "COMPLETED") c.done = true;
            else failed.emplace_back(k, st);
        }
        if (!failed.empty()) {
            for (const auto& [k, st] : failed) {
                const Chunk& ch = f.plan.chunks[k];
                if (f.chunks[k].attempts > retries_) {
                    const std::string log = fmt::format("{}/render_{}_{}.log", f.plan.work, f.chunks[k].owner, k);
                    const std::string said = one_line(last_log_line(log));
                    fail(i, kExitInternal,
                         fmt::format("chunk {} (samples {}:{}) failed {} time(s), last as task {}_{}: {}{} (log: {})", k,
                                     ch.begin, ch.end, f.chunks[k].attempts, f.chunks[k].owner, k, st,
                                     said.empty() ? "" : ": " + said, log));
                    return;
                }
            }
            // The merge waits on the failed task and can never run: replace it after the chunks.
            scancel(f.merge);
            try {
                for (const auto& [k, st] : failed) {
                    ChunkState& c = f.chunks[k];
                    const std::string old = c.owner;
                    c.owner = sbatch(render_sbatch_args(m_.slurm, f.plan, std::to_string(k)));
                    ++c.attempts;
                    r.attempts = std::max(r.attempts, c.attempts);
                    say(i, "chunk {} (task {}_{}) ended {}; resubmitted as job {} (attempt {}/{})", k, old, k, st, c.owner,
                        c.attempts, retries_ + 1);
                }
                submit_merge(i, merge_dependency(f));
            } catch (const ClientError& e) {
                fail(i, e.exit_code(), e.what());
            }
            return;
        }
        if (!std::all_of(f.chunks.begin(), f.chunks.end(), [](const ChunkState& c) { return c.done; })) return;
        if (queued.count(f.merge)) return;
        const std::string st = final_state(f.merge, -1, "");
        if (st.empty()) return;
        if (st == "COMPLETED" && fs::exists(f.plan.output)) {
            f.finished = true;
            r.state = "done";
            r.exit_code = kExitOk;
            r.spp = f.plan.spp;
            r.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - f.start).count();
            if (!m_.slurm.keep_parts) {
                std::error_code ec;
                for (const auto& p : f.plan.parts) fs::remove(p, ec);
            }
            say(i, "done: merge job {} wrote {}", f.merge, f.plan.output);
            return;
        }
        const std::string log = fmt::format("{}/merge_{}.log", f.plan.work, f.merge);
        const std::string said = one_line(last_log_line(log));
        const std::string why = fmt::format("merge job {} ended {}{} (log: {})", f.merge,
                                            st == "COMPLETED" ? "COMPLETED without writing the output" : st,
                                            said.empty() ? "" : ": " + said, log);
        // Exit status 2 is omega merge refusing the parts: another attempt would refuse them again.
        ++f.merge_failures;
        if (f.merge_failures > retries_ || st.find("exit 2:0") != std::string::npos) {
            fail(i, kExitInternal, why);
            return;
        }
        say(i, "{}; resubmitting it", why);
        r.attempts = std::max(r.attempts, f.merge_failures + 1);
        try {
            submit_merge(i, "");
        } catch (const ClientError& e) {
            fail(i, e.exit_code(), e.what());
        }
    }

    const BatchManifest& m_;
    std::vector<Frame> frames_;
    std::FILE* log_;
    int retries_;
    bool have_sacct_ = false;
    std::vector<BatchResult> results_;
    std::map<std::string, Lookup> cache_;
    std::string last_error_;
};

// The samples to render: the job's spp, else the scene's (64 when it names no halt). A time or
// error halt cannot be cut into sample ranges. The scene is parsed either way, so a bad one stops
// the batch (exit 2) before anything is submitted.
uint64_t frame_spp(const BatchEntry& e, std::map<std::string, HaltDesc>& parsed) {
    auto it = parsed.find(e.scene);
    if (it == parsed.end()) {
        try {
            it = parsed.emplace(e.scene, parse_scene_file(e.scene).sensor.halt).first;
        } catch (const SceneError& x) {
            throw ClientError(kExitBadInput, fmt::format("{}\n  (scene of the job at {})", x.what(), e.where));
        }
    }
    if (e.spec.halt.spp) return *e.spec.halt.spp;
    if (e.spec.halt.time_s || e.spec.halt.target_error)
        throw ClientError(kExitBadInput, fmt::format("{}: {}: --slurm splits a sample count; give the job `spp`, not "
                                                     "`time` or `target_error`", e.where, e.label));
    const HaltDesc& h = it->second;
    if (h.time_s || h.target_error)
        throw ClientError(kExitBadInput, fmt::format("{}: {}: the scene halts on time or error, which --slurm cannot "
                                                     "split; give the job `spp`", e.where, e.label));
    return h.spp ? uint64_t(*h.spp) : 64;
}

}  // namespace

std::vector<BatchResult> run_slurm_batch(const BatchManifest& m, bool dry_run, std::FILE* out, std::FILE* log) {
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    const std::string omega_bin = ec ? "omega" : self.string();
    // Every scene is read before anything is submitted: a bad one stops the batch at once.
    std::vector<Frame> frames;
    std::map<std::string, HaltDesc> parsed;
    for (size_t i = 0; i < m.jobs.size(); ++i) {
        Frame f;
        f.plan = plan_frame(m, i, frame_spp(m.jobs[i], parsed), omega_bin);
        f.chunks.resize(f.plan.chunks.size());
        frames.push_back(std::move(f));
    }
    if (dry_run) {
        for (size_t i = 0; i < frames.size(); ++i) {
            const FramePlan& p = frames[i].plan;
            fmt::print(out, "# [{}/{}] {} -> {}\n# {}:\n{}", i + 1, frames.size(), p.entry->label, p.output,
                       p.render_script, p.render_text);
            auto q = [](std::vector<std::string> v) {
                for (auto& a : v) a = sh_quote(a);
                return join(v, " ");
            };
            fmt::print(out, "# {}:\n{}", p.merge_script, p.merge_text);
            fmt::print(out, "$ sbatch {}\n", q(render_sbatch_args(m.slurm, p, fmt::format("0-{}", p.chunks.size() - 1))));
            fmt::print(out, "$ sbatch {}\n\n", q(merge_sbatch_args(m.slurm, p, "afterok:ARRAY_JOB_ID")));
        }
        std::fflush(out);
        return {};
    }
    return SlurmRunner(m, std::move(frames), log).run();
}

}  // namespace omega::client::slurm
