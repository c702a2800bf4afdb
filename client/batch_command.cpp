#include "batch_command.h"

#include <fmt/args.h>
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <atomic>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "film/film.h"
#include "remote_common.h"
#include "slurm_batch.h"

namespace omega::client {

namespace fs = std::filesystem;
namespace proto = omega::protocol;

// ---------------------------------------------------------------- manifest

namespace {

struct ManifestParser {
    std::string file;

    [[noreturn]] void fail(const YAML::Node& n, const std::string& key, const std::string& what) const {
        const int line = n.IsDefined() && n.Mark().line >= 0 ? n.Mark().line + 1 : 1;
        throw ClientError(kExitBadInput, fmt::format("{}:{}: {}{}{}", file, line, key, key.empty() ? "" : ": ", what));
    }
    std::string str(const YAML::Node& n, const std::string& key) const {
        if (!n.IsScalar()) fail(n, key, "expected a string");
        return n.Scalar();
    }
    long long integer(const YAML::Node& n, const std::string& key, long long lo, long long hi) const {
        if (!n.IsScalar()) fail(n, key, "expected an integer");
        const std::string& s = n.Scalar();
        long long v = 0;
        auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (s.empty() || ec != std::errc() || p != s.data() + s.size()) fail(n, key, "expected an integer");
        if (v < lo || v > hi) fail(n, key, fmt::format("must be in {}..{}", lo, hi));
        return v;
    }
    double number(const YAML::Node& n, const std::string& key, double lo, double hi) const {
        if (!n.IsScalar()) fail(n, key, "expected a number");
        double v = 0;
        try {
            size_t used = 0;
            v = std::stod(n.Scalar(), &used);
            if (used != n.Scalar().size()) throw std::invalid_argument("");
        } catch (const std::exception&) {
            fail(n, key, "expected a number");
        }
        if (!(v > lo && v <= hi)) fail(n, key, fmt::format("must be in ({}, {}]", lo, hi));
        return v;
    }
};

struct Var {
    std::string name;
    std::vector<std::string> values;  // as written; integers are formatted as integers
};

// Formats text with the matrix values ({frame}, {frame:04}, {sensor}).
std::string substitute(const ManifestParser& P, const YAML::Node& at, const std::string& key, const std::string& text,
                       const std::vector<std::pair<std::string, std::string>>& values) {
    if (values.empty()) return text;
    fmt::dynamic_format_arg_store<fmt::format_context> store;
    for (const auto& [name, v] : values) {
        long long iv = 0;
        auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), iv);
        if (!v.empty() && ec == std::errc() && p == v.data() + v.size())
            store.push_back(fmt::arg(name.c_str(), iv));
        else
            store.push_back(fmt::arg(name.c_str(), v));
    }
    try {
        return fmt::vformat(text, store);
    } catch (const fmt::format_error& e) {
        P.fail(at, key, fmt::format("cannot fill in '{}': {}", text, e.what()));
    }
}

// The `slurm:` mapping. Paths in it are relative to the manifest's folder, like output_dir.
void parse_slurm(const ManifestParser& P, const YAML::Node& v, const fs::path& dir, SlurmSettings& s) {
    if (!v.IsMap()) P.fail(v, "slurm", "expected a mapping");
    auto word = [&](const YAML::Node& n, const std::string& key) {
        std::string w = P.str(n, key);
        if (w.empty() || w.find_first_of(" \t\r\n") != std::string::npos) P.fail(n, key, "expected one word");
        return w;
    };
    auto path = [&](const YAML::Node& n, const std::string& key) {
        fs::path p = P.str(n, key);
        if (p.empty()) P.fail(n, key, "expected a path");
        return (p.is_relative() ? fs::absolute(dir / p) : p).lexically_normal().string();
    };
    for (const auto& kv : v) {
        const std::string k = kv.first.Scalar();
        const std::string key = "slurm." + k;
        const YAML::Node& x = kv.second;
        if (k == "partition") s.partition = word(x, key);
        else if (k == "chunks") s.chunks = int(P.integer(x, key, 1, 10000));
        else if (k == "time_limit") {
            // sbatch's own formats: minutes, MM:SS, HH:MM:SS, D-HH[:MM[:SS]], or UNLIMITED.
            std::string t = word(x, key);
            if (t != "UNLIMITED" && t != "INFINITE" &&
                (t.find_first_not_of("0123456789:-") != std::string::npos || !std::isdigit(uint8_t(t.front())) ||
                 !std::isdigit(uint8_t(t.back()))))
                P.fail(x, key, "expected minutes, [D-]HH:MM:SS or UNLIMITED");
            s.time_limit = t;
        } else if (k == "retries") s.retries = int(P.integer(x, key, 0, 100));
        else if (k == "cpus_per_task") s.cpus_per_task = int(P.integer(x, key, 1, 4096));
        else if (k == "poll_interval") {
            // A floor, because every poll forks squeue and scontrol against a shared controller.
            s.poll_interval_s = P.number(x, key, 0, 3600);
            if (s.poll_interval_s < SlurmSettings::kMinPollInterval)
                P.fail(x, key, fmt::format("at least {} s (each poll queries the Slurm controller)", SlurmSettings::kMinPollInterval));
        }
        else if (k == "omega") s.omega = path(x, key);
        else if (k == "work_dir") s.work_dir = path(x, key);
        else if (k == "keep_parts") {
            const std::string b = P.str(x, key);
            if (b != "true" && b != "false") P.fail(x, key, "expected true or false");
            s.keep_parts = b == "true";
        } else if (k == "sbatch_args") {
            if (!x.IsSequence()) P.fail(x, key, "expected a list of arguments, e.g. [--qos=high, --mem=2G]");
            s.sbatch_args.clear();
            for (const auto& a : x) {
                std::string arg = P.str(a, key);
                if (arg.empty()) P.fail(a, key, "an empty argument");
                s.sbatch_args.push_back(std::move(arg));
            }
        } else {
            P.fail(kv.first, key,
                   "unknown key (partition, chunks, time_limit, retries, cpus_per_task, sbatch_args, poll_interval, "
                   "omega, work_dir, keep_parts)");
        }
    }
}

const std::set<std::string> kJobKeys{"scene", "output", "priority", "spp", "time", "target_error",
                                     "seed", "integrator", "frames", "matrix"};

}  // namespace

BatchManifest parse_manifest(const std::string& path) {
    ManifestParser P{path};
    BatchManifest m;
    m.path = path;
    YAML::Node root;
    try {
        root = YAML::LoadFile(path);
    } catch (const YAML::BadFile&) {
        throw ClientError(kExitBadInput, fmt::format("{}: cannot open the manifest", path));
    } catch (const YAML::Exception& e) {
        throw ClientError(kExitBadInput, fmt::format("{}:{}: invalid YAML: {}", path, std::max(e.mark.line + 1, 1), e.msg));
    }
    if (!root.IsMap()) P.fail(root, "", "a manifest is a mapping with a `jobs` list");
    const fs::path dir = fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path();
    fs::path out_dir = dir;
    YAML::Node defaults;
    for (const auto& kv : root) {
        const std::string k = kv.first.Scalar();
        const YAML::Node& v = kv.second;
        if (k == "host") m.host = P.str(v, k);
        else if (k == "concurrency") m.concurrency = int(P.integer(v, k, 1, 1024));
        else if (k == "retries") m.retries = int(P.integer(v, k, 0, 100));
        else if (k == "retry_delay") m.retry_delay_s = P.number(v, k, -1e-300, 3600);
        else if (k == "poll_interval") m.poll_interval_s = P.number(v, k, 0, 3600);
        else if (k == "output_dir") {
            fs::path p = P.str(v, k);
            out_dir = p.is_relative() ? dir / p : p;
        } else if (k == "defaults") {
            if (!v.IsMap()) P.fail(v, k, "expected a mapping of job keys");
            defaults = v;
        } else if (k == "slurm") {
            parse_slurm(P, v, dir, m.slurm);
        } else if (k != "jobs") {
            P.fail(kv.first, k, "unknown key (host, concurrency, retries, retry_delay, poll_interval, output_dir, defaults, slurm, jobs)");
        }
    }
    m.output_dir = out_dir.lexically_normal().string();
    const YAML::Node jobs = root["jobs"];
    if (!jobs) P.fail(root, "jobs", "missing");
    if (!jobs.IsSequence() || jobs.size() == 0) P.fail(jobs, "jobs", "expected a non-empty list");

    std::map<std::string, std::string> outputs;  // output path -> where
    for (size_t i = 0; i < jobs.size(); ++i) {
        const YAML::Node j = jobs[i];
        const std::string key = fmt::format("jobs[{}]", i);
        if (!j.IsMap()) P.fail(j, key, "expected a mapping with at least `scene`");
        // The job's own keys win over the defaults.
        std::map<std::string, YAML::Node> keys;
        // A halt the job gives replaces the defaults' halt instead of conflicting with it.
        const bool own_halt = j["spp"] || j["time"] || j["target_error"];
        auto is_halt = [](const std::string& k) { return k == "spp" || k == "time" || k == "target_error"; };
        for (const YAML::Node* src : std::initializer_list<const YAML::Node*>{&defaults, &j}) {
            if (!*src) continue;
            for (const auto& kv : *src) {
                const std::string k = kv.first.Scalar();
                if (!kJobKeys.count(k))
                    P.fail(kv.first, src == &j ? key + "." + k : "defaults." + k,
                           "unknown key (scene, output, priority, spp, time, target_error, seed, integrator, frames, matrix)");
                if (src == &defaults && own_halt && is_halt(k)) continue;
                keys[k] = kv.second;
            }
        }
        auto has = [&](const char* k) { return keys.count(k) > 0; };
        if (!has("scene")) P.fail(j, key + ".scene", "missing");
        int halts = int(has("spp")) + int(has("time")) + int(has("target_error"));
        if (halts > 1) P.fail(j, key, "give at most one of spp, time, target_error");

        JobSpec spec;
        if (has("priority")) spec.priority = P.integer(keys["priority"], key + ".priority", proto::kMinPriority, proto::kMaxPriority);
        if (has("spp")) spec.halt.spp = uint64_t(P.integer(keys["spp"], key + ".spp", 1, 1LL << 40));
        if (has("time")) spec.halt.time_s = P.number(keys["time"], key + ".time", 0, 1e9);
        if (has("target_error")) spec.halt.target_error = P.number(keys["target_error"], key + ".target_error", 0, 1e6);
        if (has("seed")) spec.seed = uint64_t(P.integer(keys["seed"], key + ".seed", 0, std::numeric_limits<long long>::max()));
        if (has("integrator")) {
            std::string v = P.str(keys["integrator"], key + ".integrator");
            if (v != "path" && v != "light" && v != "bdpt") P.fail(keys["integrator"], key + ".integrator", "one of path, light, bdpt");
            spec.integrator = v;
        }

        std::vector<Var> vars;
        if (has("frames")) {
            const YAML::Node f = keys["frames"];
            Var v{"frame", {}};
            if (f.IsScalar()) {
                v.values.push_back(std::to_string(P.integer(f, key + ".frames", -1000000000, 1000000000)));
            } else if (f.IsSequence() && f.size() == 2) {
                long long a = P.integer(f[0], key + ".frames[0]", -1000000000, 1000000000);
                long long b = P.integer(f[1], key + ".frames[1]", a, a + 100000);
                for (long long x = a; x <= b; ++x) v.values.push_back(std::to_string(x));
            } else {
                P.fail(f, key + ".frames", "expected [first, last] (inclusive) or one frame number");
            }
            vars.push_back(std::move(v));
        }
        if (has("matrix")) {
            const YAML::Node mx = keys["matrix"];
            if (!mx.IsMap()) P.fail(mx, key + ".matrix", "expected a mapping of name: [values]");
            for (const auto& kv : mx) {
                const std::string name = kv.first.Scalar();
                const std::string mk = key + ".matrix." + name;
                if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") != std::string::npos)
                    P.fail(kv.first, mk, "names are [a-z0-9_]+");
                if (!kv.second.IsSequence() || kv.second.size() == 0) P.fail(kv.second, mk, "expected a non-empty list");
                Var v{name, {}};
                for (const auto& x : kv.second) v.values.push_back(P.str(x, mk));
                vars.push_back(std::move(v));
            }
        }
        const std::string scene_t = P.str(keys["scene"], key + ".scene");
        const std::optional<std::string> output_t =
            has("output") ? std::optional(P.str(keys["output"], key + ".output")) : std::nullopt;
        if (!vars.empty() && output_t && output_t->find('{') == std::string::npos)
            P.fail(keys["output"], key + ".output", "with frames or matrix, the output must use them, e.g. out_{frame:04}.exr");

        // Cartesian product of the variables, first one slowest.
        size_t total = 1;
        for (const auto& v : vars) total *= v.values.size();
        if (total > 100000) P.fail(j, key, "expands to more than 100000 jobs");
        for (size_t n = 0; n < total; ++n) {
            std::vector<std::pair<std::string, std::string>> values(vars.size());
            for (size_t k = vars.size(), rest = n; k-- > 0; rest /= vars[k].values.size())
                values[k] = {vars[k].name, vars[k].values[rest % vars[k].values.size()]};
            BatchEntry e;
            e.where = fmt::format("{}:{}", path, j.Mark().line + 1);
            e.spec = spec;
            // A variable named like a job key also sets that key: matrix: {seed: [1, 2, 3]}.
            for (const auto& [n, v] : values) {
                const YAML::Node at = keys.count("matrix") ? keys["matrix"] : keys["frames"];
                const YAML::Node val(v);
                const std::string vk = key + ".matrix." + n;
                try {
                    if (n == "seed") e.spec.seed = uint64_t(P.integer(val, vk, 0, std::numeric_limits<long long>::max()));
                    if (n == "priority") e.spec.priority = P.integer(val, vk, proto::kMinPriority, proto::kMaxPriority);
                    if (n == "spp") e.spec.halt = proto::Halt{uint64_t(P.integer(val, vk, 1, 1LL << 40)), {}, {}};
                } catch (const ClientError&) {
                    P.fail(at, vk, fmt::format("'{}' is not a valid {}", v, n));
                }
                if (n == "integrator") {
                    if (v != "path" && v != "light" && v != "bdpt") P.fail(at, vk, "one of path, light, bdpt");
                    e.spec.integrator = v;
                }
            }
            const std::string scene = substitute(P, keys["scene"], key + ".scene", scene_t, values);
            const fs::path sp = fs::path(scene).is_relative() ? dir / scene : fs::path(scene);
            e.scene = sp.lexically_normal().string();
            std::string out;
            if (output_t) {
                out = substitute(P, keys["output"], key + ".output", *output_t, values);
            } else {
                out = fs::path(scene).stem().string();
                for (const auto& [n, v] : values) out += "_" + v;
                out += ".exr";
            }
            const fs::path op = fs::path(out).is_relative() ? out_dir / out : fs::path(out);
            e.output = op.lexically_normal().string();
            e.label = scene;
            for (const auto& [n, v] : values) e.label += fmt::format(" {}={}", n, v);
            if (auto [it, fresh] = outputs.emplace(e.output, e.where); !fresh)
                P.fail(j, key, fmt::format("output {} is also written by the job at {}", e.output, it->second));
            m.jobs.push_back(std::move(e));
        }
    }
    return m;
}

// ---------------------------------------------------------------- running

namespace {

class Runner {
public:
    Runner(const BatchManifest& m, Address addr, std::FILE* log, std::vector<ScannedScene> scenes)
        : m_(m), addr_(std::move(addr)), log_(log), scenes_(std::move(scenes)) {}

    std::vector<BatchResult> run() {
        results_.resize(m_.jobs.size());
        for (size_t i = 0; i < m_.jobs.size(); ++i) results_[i].entry = &m_.jobs[i];
        const size_t n = std::min(size_t(m_.concurrency), m_.jobs.size());
        std::vector<std::thread> workers;
        for (size_t w = 0; w < n; ++w)
            workers.emplace_back([this] {
                for (size_t i; (i = next_++) < m_.jobs.size();) run_one(i);
            });
        for (auto& t : workers) t.join();
        return std::move(results_);
    }

private:
    template <class... A>
    void say(size_t i, fmt::format_string<A...> f, A&&... a) {
        if (!log_) return;
        std::lock_guard lock(log_mu_);
        fmt::print(log_, "[{}/{}] {}: {}\n", i + 1, m_.jobs.size(), m_.jobs[i].label, fmt::format(f, std::forward<A>(a)...));
        std::fflush(log_);
    }

    static void sleep_s(double s) { std::this_thread::sleep_for(std::chrono::duration<double>(s)); }

    void run_one(size_t i) {
        const BatchEntry& e = m_.jobs[i];
        BatchResult& r = results_[i];
        const int max_attempts = 1 + m_.retries;
        std::optional<Connection> c;
        std::string why;  // last transient failure
        while (r.attempts < max_attempts) {
            ++r.attempts;
            if (r.attempts > 1) {
                say(i, "retrying (attempt {}/{}) after: {}", r.attempts, max_attempts, why);
                sleep_s(m_.retry_delay_s);
            }
            try {
                if (!c) c.emplace(Connection::open(addr_, ConnectOptions{}));
                if (!r.job) {
                    r.job = submit_scene(*c, scenes_[i], e.spec).job;
                    say(i, "submitted as job {}", *r.job);
                }
                // Wait for the job to end.
                proto::JobInfo info;
                for (;;) {
                    proto::Status st{c->next_id(), *r.job};
                    auto reply = c->request(proto::encode(st), st.id);
                    if (reply.type == proto::MessageType::error) {
                        auto err = proto::decode<proto::Error>(reply);
                        if (err && err->code == proto::ErrorCode::unknown_job)  // lost by the daemon: submit again
                            throw ClientError(kExitUnreachable, fmt::format("job {} vanished from the daemon", *r.job), true);
                    }
                    info = c->expect<proto::JobInfoReply>(reply).info;
                    if (is_terminal(info.state)) break;
                    sleep_s(m_.poll_interval_s);
                }
                r.spp = info.progress.spp;
                r.elapsed_s = info.progress.elapsed_s;
                if (info.state == proto::JobState::cancelled) {
                    r.state = "cancelled";
                    r.exit_code = kExitInternal;
                    r.message = "cancelled on the daemon";
                    say(i, "job {} was cancelled", *r.job);
                    return;
                }
                if (info.state == proto::JobState::failed) {
                    why = fmt::format("job {} failed", *r.job);
                    r.state = "failed";
                    r.exit_code = kExitInternal;
                    r.message = why;
                    r.job.reset();  // a new attempt submits again
                    continue;
                }
                proto::Fetch f{c->next_id(), *r.job};
                auto img = c->expect<proto::Image>(c->request(proto::encode(f), f.id));
                std::error_code ec;
                const fs::path parent = fs::path(e.output).parent_path();
                if (!parent.empty()) fs::create_directories(parent, ec);
                try {
                    write_file_atomic(e.output, std::span(reinterpret_cast<const uint8_t*>(img.exr.data()), img.exr.size()));
                } catch (const std::exception& x) {
                    r.state = "error";
                    r.exit_code = kExitInternal;
                    r.message = x.what();
                    say(i, "{}", r.message);
                    return;
                }
                r.state = "done";
                r.exit_code = kExitOk;
                r.message.clear();
                r.spp = img.spp;
                say(i, "done: {} spp in {} -> {}", r.spp, human_duration(r.elapsed_s), e.output);
                return;
            } catch (const ClientError& x) {
                if (!x.transient()) {
                    r.state = "error";
                    r.exit_code = x.exit_code();
                    r.message = x.what();
                    say(i, "{}", r.message);
                    return;
                }
                why = x.what();
                r.state = "error";
                r.exit_code = x.exit_code();
                r.message = why;
                c.reset();  // reconnect; a job already accepted keeps its id and is waited for again
            }
        }
        say(i, "gave up after {} attempt(s): {}", r.attempts, r.message);
    }

    const BatchManifest& m_;
    Address addr_;
    std::FILE* log_;
    std::vector<ScannedScene> scenes_;
    std::vector<BatchResult> results_;
    std::atomic<size_t> next_{0};
    std::mutex log_mu_;
};

}  // namespace

std::vector<BatchResult> run_batch_jobs(const BatchManifest& m, const std::optional<std::string>& host_flag,
                                        std::FILE* log) {
    const Address addr = resolve_address(host_flag ? host_flag : m.host);
    // Every scene is read and hashed before anything is sent: a bad one stops the batch at once.
    std::map<std::string, ScannedScene> cache;
    std::vector<ScannedScene> scenes;
    for (const auto& e : m.jobs) {
        auto it = cache.find(e.scene);
        if (it == cache.end()) {
            try {
                it = cache.emplace(e.scene, scan_scene(e.scene)).first;
            } catch (const ClientError& x) {
                throw ClientError(x.exit_code(), fmt::format("{}\n  (scene of the job at {})", x.what(), e.where));
            }
        }
        scenes.push_back(it->second);
    }
    return Runner(m, addr, log, std::move(scenes)).run();
}

std::string format_summary(const std::vector<BatchResult>& results) {
    std::vector<std::vector<std::string>> rows{{"#", "SCENE", "JOB", "STATE", "TRIES", "SPP", "TIME", "OUTPUT"}};
    size_t ok = 0;
    for (size_t i = 0; i < results.size(); ++i) {
        const auto& r = results[i];
        ok += r.state == "done";
        rows.push_back({std::to_string(i + 1), r.entry->label, r.job ? std::to_string(*r.job) : "-", r.state,
                        std::to_string(r.attempts), r.state == "done" ? std::to_string(r.spp) : "-",
                        r.state == "done" ? human_duration(r.elapsed_s) : "-",
                        r.state == "done" ? r.entry->output : r.message});
    }
    return format_table(rows) + fmt::format("{} of {} job(s) done, {} failed\n", ok, results.size(), results.size() - ok);
}

void add_batch_command(CLI::App& app, BatchArgs& a) {
    auto* cmd = app.add_subcommand("batch", "Render every job of a manifest on the daemon; waits and writes every output");
    cmd->add_option("manifest", a.manifest, "Batch manifest (YAML, see docs/client.md)")->required();
    add_host_option(cmd, a.host);
    cmd->add_option("-j,--concurrency", a.concurrency, "Jobs in flight at once (overrides the manifest)")
        ->check(CLI::Range(1, 1024));
    cmd->add_flag("--slurm", a.slurm, "Submit to Slurm: a job array of sample chunks and a merge job per job (the manifest's `slurm:` keys)");
    cmd->add_flag("--dry-run", a.dry_run, "With --slurm: print the scripts and sbatch commands, submit nothing");
}

int run_batch(const BatchArgs& a) {
    return guarded([&] {
        BatchManifest m = parse_manifest(a.manifest);
        if (a.concurrency) m.concurrency = *a.concurrency;
        if (a.dry_run && !a.slurm) throw ClientError(kExitBadInput, "--dry-run needs --slurm");
        if (a.slurm && a.dry_run) {
            slurm::run_slurm_batch(m, true, stdout, stderr);
            return kExitOk;
        }
        const auto results = a.slurm ? slurm::run_slurm_batch(m, false, stdout, stderr) : run_batch_jobs(m, a.host, stderr);
        std::fputs(format_summary(results).c_str(), stdout);
        std::fflush(stdout);
        for (const auto& r : results)
            if (r.state != "done") return r.exit_code ? r.exit_code : kExitInternal;
        return kExitOk;
    });
}

}  // namespace omega::client
