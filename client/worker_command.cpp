// omega worker. One thread talks to the daemon (this one, blocking reads with short deadlines);
// one render thread runs the current unit's RenderSession, which the talking thread aborts on
// unit_stop or a lost connection. No other state is shared between them.
#include "worker_command.h"

#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <chrono>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

#include "asset_scan.h"
#include "connection.h"
#include "film/film.h"
#include "film/partial_exr.h"
#include "integrator/render_session.h"
#include "pathspace/classify.h"
#include "remote_common.h"
#include "io/file_gate.h"
#include "scene/scene_parser.h"
#include "scene/scene.h"
#include "scene/scene_error.h"
#include "scene_hash.h"
#include "session_outputs.h"

namespace omega::client {

namespace proto = omega::protocol;
namespace fs = std::filesystem;

namespace {

// A scene as the daemon's job directory holds it, rebuilt under the cache: files/NAME.yaml beside
// its assets, so relative names resolve as they do in the daemon and in `omega render`.
struct LocalScene {
    std::string key;  // sha256 over scene text, asset hashes and overrides
    std::string path;
    SceneDesc desc;
    std::unique_ptr<Scene> scene;
    std::vector<std::string> warnings;
    std::string hash;  // omega.scene_hash, as `omega render --samples` writes it
};

// The daemon's name for the job's scene file (daemon/job_scene.cpp, scene_file_name).
std::string scene_file(const std::string& job_name) {
    bool ok = !job_name.empty() && job_name.size() <= 200 && job_name[0] != '.';
    for (char c : job_name)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) ok = false;
    return (ok ? job_name : std::string("scene")) + ".yaml";
}

void write_file(const std::string& path, const std::string& data) {
    fs::create_directories(fs::path(path).parent_path());
    const std::string tmp = path + ".tmp" + std::to_string(::getpid());
    {
        std::ofstream out(tmp, std::ios::binary);
        out.write(data.data(), std::streamsize(data.size()));
        if (!out) throw ClientError(kExitInternal, "cannot write " + tmp);
    }
    fs::rename(tmp, path);
}

std::string read_whole(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// Reads frames until the one answering `id`; pings are answered, a unit_stop for the unit in hand
// sets *stopped. Throws ClientError (transient) when the connection is lost.
proto::DecodedFrame await(Connection& c, uint64_t id, std::atomic<bool>* stopped = nullptr,
                          const std::pair<uint64_t, uint64_t>* unit = nullptr) {
    for (;;) {
        proto::DecodedFrame f = c.read(Clock::now() + std::chrono::hours(24));
        if (f.type == proto::MessageType::ping) {
            c.send(proto::encode(proto::Pong{f.id}));
            continue;
        }
        if (f.type == proto::MessageType::unit_stop) {
            auto s = proto::decode<proto::UnitStop>(f);
            if (s && unit && stopped && s->job == unit->first && s->unit == unit->second) stopped->store(true);
            continue;
        }
        if (f.id == id) return f;
    }
}

class Worker {
public:
    explicit Worker(const WorkerArgs& a) : a_(a) {
        char host[256] = {0};
        ::gethostname(host, sizeof host - 1);
        name_ = a.name.empty() ? fmt::format("{}:{}", host, ::getpid()) : a.name;
        cache_ = a.cache_dir.empty() ? (fs::temp_directory_path() / fmt::format("omega-worker-{}", ::getuid())).string()
                                     : a.cache_dir;
    }

    // One session: units until the connection ends (throws ClientError) or, with --once, until
    // the daemon has none (returns).
    void serve(Connection& c) {
        for (;;) {
            proto::WorkRequest req{c.next_id(), static_cast<uint32_t>(resolve_threads(a_.threads)), name_};
            c.send(proto::encode(req));
            // Wait for the unit; with an idle limit, give up (and exit) when none comes in time.
            const double idle = a_.idle_exit_s > 0 ? a_.idle_exit_s : a_.once ? 3.0 : 0.0;
            const auto give_up = idle > 0 ? Clock::now() + std::chrono::milliseconds(static_cast<long>(idle * 1000))
                                          : Clock::time_point::max();
            std::optional<proto::DecodedFrame> f;
            while (!f) {
                const auto until = std::min(give_up, Clock::now() + std::chrono::seconds(60));
                auto got = c.try_read(until);
                if (!got) {
                    if (Clock::now() >= give_up) {
                        if (!a_.quiet) fmt::print(stderr, "omega worker: no unit for {} s; exiting\n", idle);
                        return;
                    }
                    continue;
                }
                if (got->type == proto::MessageType::ping) c.send(proto::encode(proto::Pong{got->id}));
                else if (got->id == req.id) f = std::move(got);  // stray unit_stops are for units already given up
            }
            const proto::WorkUnit u = c.expect<proto::WorkUnit>(*f);
            run_unit(c, u);
        }
    }

private:
    LocalScene& prepare(Connection& c, const proto::WorkUnit& u) {
        std::string keytext = u.scene + "\n" + u.name + "\n" + u.integrator.value_or("") + "\n" + u.sampler.value_or("");
        for (const auto& a : u.assets) keytext += "\n" + a.name + " " + a.sha256;
        const std::string key = sha256_bytes(keytext);
        if (scene_ && scene_->key == key) return *scene_;
        scene_.reset();
        const std::string dir = fs::absolute(cache_ + "/" + key.substr(0, 24) + "/files").lexically_normal().string();
        for (const auto& a : u.assets) {
            const std::string path = dir + "/" + a.name;
            std::error_code ec;
            if (fs::exists(path, ec) && fs::file_size(path, ec) == a.size && sha256_file(path) == a.sha256) continue;
            proto::AssetRequest r{c.next_id(), u.job, a.sha256};
            c.send(proto::encode(r));
            const proto::Asset got = c.expect<proto::Asset>(await(c, r.id));
            if (got.data.size() != a.size || sha256_bytes(got.data) != a.sha256)
                throw ClientError(kExitInternal, fmt::format("asset {} ({}) arrived damaged", a.name, a.sha256));
            write_file(path, got.data);
        }
        auto s = std::make_unique<LocalScene>();
        s->key = key;
        s->path = dir + "/" + scene_file(u.name);
        write_file(s->path, u.scene);
        // Confined to the job's own files, as in the daemon: a scene from the daemon never reads
        // anything else on this machine.
        s->desc = parse_scene_string(u.scene, s->path, FileGate::confined({dir}));
        if (u.integrator == "path") s->desc.integrator.type = IntegratorType::Path;
        if (u.integrator == "light") s->desc.integrator.type = IntegratorType::Light;
        if (u.integrator == "bdpt") s->desc.integrator.type = IntegratorType::Bdpt;
        if (u.sampler)
            if (auto t = sampler_from_name(*u.sampler)) s->desc.integrator.sampler = *t;
        s->scene = Scene::build(s->desc);
        s->warnings = s->desc.warnings;
        for (const auto& w : s->scene->warnings()) s->warnings.push_back(w);
        for (auto& w : path_space_warnings(*s->scene, s->desc.integrator.type)) s->warnings.push_back(std::move(w));
        s->hash = scene_content_hash(s->path, s->desc, {});
        scene_ = std::move(s);
        return *scene_;
    }

    void run_unit(Connection& c, const proto::WorkUnit& u) {
        const std::pair<uint64_t, uint64_t> id{u.job, u.unit};
        std::atomic<bool> stopped{false};
        LocalScene* ls = nullptr;
        try {
            ls = &prepare(c, u);
        } catch (const SceneError& e) {
            // The daemon built this scene when it accepted the job; a worker that cannot is broken
            // itself (a missing file system, another version): leave rather than take more units.
            throw ClientError(kExitInternal, fmt::format("job {}: cannot build the scene: {}", u.job, e.what()));
        }
        if (!a_.quiet)
            fmt::print(stderr, "omega worker: job {} unit {}: samples {}:{}\n", u.job, u.unit, u.begin, u.end);
        // Exactly `omega render --samples BEGIN:END` (render_command.cpp).
        RenderSettings rs;
        rs.halt = HaltDesc{static_cast<long long>(u.end), std::nullopt, std::nullopt};
        rs.first_sample = static_cast<long long>(u.begin);
        rs.threads = a_.threads;
        rs.seed = u.seed;
        rs.integrator = ls->desc.integrator;
        RenderSession session(*ls->scene, rs);
        PassReport last{};
        std::exception_ptr failure;
        std::atomic<bool> finished{false};
        std::thread render([&] {  // the render thread
            try {
                last = session.run([](const PassReport&) {});
            } catch (...) {
                failure = std::current_exception();
            }
            finished.store(true);
        });
        // This thread: watch the connection while the unit renders.
        try {
            while (!finished.load()) {
                // 10 ms: the unit's end is noticed within that (the wait was 100 ms, most of the
                // 83 ms gap per unit bench/farm_overhead.py measured); 100 wake-ups a second cost
                // nothing beside a render.
                auto f = c.try_read(Clock::now() + std::chrono::milliseconds(10));
                if (!f) continue;
                if (f->type == proto::MessageType::ping) c.send(proto::encode(proto::Pong{f->id}));
                if (f->type == proto::MessageType::unit_stop) {
                    auto s = proto::decode<proto::UnitStop>(*f);
                    if (s && s->job == u.job && s->unit == u.unit) {
                        stopped.store(true);
                        session.abort();
                    }
                }
            }
        } catch (...) {
            session.abort();  // the daemon is gone: the unit is handed out again there
            render.join();
            throw;
        }
        render.join();
        if (failure) std::rethrow_exception(failure);
        if (stopped.load() || session.aborted()) {
            if (!a_.quiet) fmt::print(stderr, "omega worker: job {} unit {}: stopped by the daemon\n", u.job, u.unit);
            return;
        }
        ExrMeta meta;
        meta.spp = last.spp - rs.first_sample;
        meta.time_s = last.elapsed_s;
        meta.integrator = integrator_name(ls->desc.integrator.type);
        meta.seed = u.seed;
        meta.attributes["omega.sampler"] = sampler_name(ls->desc.integrator.sampler);
        meta.nonfinite = last.nonfinite;
        meta.warnings = ls->warnings;
        meta.rel_error = last.error.mean_rel_error;
        PartInfo part{{{static_cast<long long>(u.begin), last.spp}}, ls->hash, u.seed, meta.integrator,
                      sampler_name(ls->desc.integrator.sampler)};
        // The job's AOVs and breakdown go with the unit: omegad folds them as `omega merge` does.
        add_session_outputs(session, static_cast<long long>(u.begin), last.spp, true, meta);
        const std::string tmp = fmt::format("{}/part-{}-{}-{}.exr", cache_, ::getpid(), u.job, u.unit);
        write_partial_exr(tmp, session.film(), meta, part, session_aov_films(session));
        proto::UnitResult r;
        r.id = c.next_id();
        r.job = u.job;
        r.unit = u.unit;
        r.begin = u.begin;
        r.end = u.end;
        r.time_s = last.elapsed_s;
        r.samples_per_s = last.samples_per_s;
        r.part = read_whole(tmp);
        fs::remove(tmp);
        c.send(proto::encode(r));
        proto::DecodedFrame reply = await(c, r.id, &stopped, &id);
        if (reply.type == proto::MessageType::error) {
            auto e = proto::decode<proto::Error>(reply);
            fmt::print(stderr, "omega worker: job {} unit {}: not taken: {}\n", u.job, u.unit, e ? e->message : "?");
            return;
        }
        if (!a_.quiet)
            fmt::print(stderr, "omega worker: job {} unit {}: done in {:.2f} s\n", u.job, u.unit, last.elapsed_s);
    }

    const WorkerArgs& a_;
    std::string name_;
    std::string cache_;
    std::unique_ptr<LocalScene> scene_;  // the last unit's scene, kept for the next unit of its job
};

}  // namespace

void add_worker_command(CLI::App& app, WorkerArgs& a) {
    auto* cmd = app.add_subcommand("worker",
                                   "Render work units for omegad (jobs submitted with --workers); reconnects until "
                                   "stopped. Credentials as for other TCP clients: $OMEGA_USER, $OMEGA_TOKEN or "
                                   "$OMEGA_TOKEN_FILE");
    cmd->add_option("--connect", a.connect, "Daemon address: tcp:HOST:PORT or unix:PATH (default as for --host)");
    cmd->add_option("--threads", a.threads, "Render threads (default: all cores)")->check(CLI::NonNegativeNumber);
    cmd->add_option("--name", a.name, "Name shown by `omega status JOB` (default HOST:PID)");
    cmd->add_option("--cache", a.cache_dir, "Folder for scenes and assets (default $TMPDIR/omega-worker-UID)");
    cmd->add_flag("--once", a.once, "Exit when the daemon has no unit to give within 3 s (instead of waiting)");
    cmd->add_option("--idle-exit", a.idle_exit_s, "Exit after this many seconds without a unit (default: never)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_flag("-q,--quiet", a.quiet, "Print only errors");
}

int run_worker(const WorkerArgs& a) {
    return guarded([&] {
        Worker w(a);
        auto backoff = std::chrono::milliseconds(250);
        for (;;) {
            try {
                Connection c = connect_to(a.connect);
                backoff = std::chrono::milliseconds(250);
                if (!a.quiet) fmt::print(stderr, "omega worker: connected to {}\n", c.address().text());
                w.serve(c);
                c.close();
                return kExitOk;  // --once or --idle-exit, and nothing to do
            } catch (const ClientError& e) {
                if (!e.transient()) throw;  // refused credentials, a broken worker: retrying cannot help
                if (!a.quiet) fmt::print(stderr, "omega worker: {}; reconnecting in {} ms\n", e.what(), backoff.count());
            }
            std::this_thread::sleep_for(backoff);
            backoff = std::min(backoff * 2, std::chrono::milliseconds(5000));
        }
    });
}

}  // namespace omega::client
