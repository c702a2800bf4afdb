// `omega watch JOB [-o OUT.exr]`: subscribes to a job's tiles, keeps OUT.exr current with atomic
// replaces, shows a progress bar, and exits when the job ends.
#include <fmt/format.h>

#include <cstdio>

#include "job_commands.h"
#include "progress_bar.h"
#include "remote_common.h"
#include "tile_canvas.h"

namespace omega::client {

namespace proto = omega::protocol;

namespace {

std::string default_output(const proto::JobInfo& info) {
    return (info.name.empty() ? fmt::format("job-{}", info.job) : info.name) + ".exr";
}

int exit_for_end(proto::JobState s, uint64_t job, const std::optional<std::string>& message) {
    if (s == proto::JobState::done) return kExitOk;
    std::fprintf(stderr, "omega: job %llu %s%s%s\n", (unsigned long long)job, std::string(proto::to_string(s)).c_str(),
                 message ? ": " : "", message ? message->c_str() : "");
    return kExitInternal;
}

// Writes the daemon's current image (a job that already ended streams nothing).
bool fetch_into(Connection& c, uint64_t job, const std::string& out) {
    proto::Fetch f{c.next_id(), job};
    auto reply = c.request(proto::encode(f), f.id);
    if (reply.type == proto::MessageType::error) {
        auto e = proto::decode<proto::Error>(reply);
        if (e && e->code == proto::ErrorCode::invalid_state) return false;  // no pass completed
    }
    auto img = c.expect<proto::Image>(reply);
    write_file_atomic(out, std::span(reinterpret_cast<const uint8_t*>(img.exr.data()), img.exr.size()));
    return true;
}

}  // namespace

int run_watch(const JobArgs& a) {
    return guarded([&] {
        Connection c = connect_to(a.host);
        const uint64_t job = *a.job;
        proto::Status st{c.next_id(), job};
        const proto::JobInfo info = c.expect<proto::JobInfoReply>(c.request(proto::encode(st), st.id)).info;
        const std::string out = a.output.empty() ? default_output(info) : a.output;

        if (is_terminal(info.state)) {
            if (fetch_into(c, job, out)) std::fprintf(stderr, "omega: job %llu already ended; wrote %s\n",
                                                      (unsigned long long)job, out.c_str());
            c.close();
            return exit_for_end(info.state, job, std::nullopt);
        }

        proto::Subscribe sub{c.next_id(), job};
        c.expect<proto::Ok>(c.request(proto::encode(sub), sub.id));

        TileCanvas canvas;
        ProgressBar bar(stderr);
        bool dirty = false;
        auto last_write = Clock::now();
        const auto interval = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.write_interval_s));
        auto flush = [&] {
            if (!dirty || canvas.empty()) return;
            canvas.write(out);
            dirty = false;
            last_write = Clock::now();
        };
        std::optional<proto::Done> done;
        while (!done) {
            auto f = c.try_read(Clock::now() + std::chrono::milliseconds(250));
            if (f && f->id == sub.id) {
                switch (f->type) {
                    case proto::MessageType::tile:
                        if (canvas.apply(c.expect<proto::Tile>(*f))) dirty = true;
                        break;
                    case proto::MessageType::progress: {
                        auto p = c.expect<proto::Progress>(*f);
                        if (!a.quiet)
                            bar.update(progress_fraction(p.progress, info.halt),
                                       fmt::format("job {} {}  {}", job, proto::to_string(p.state),
                                                   format_progress(p.progress, info.halt)));
                        break;
                    }
                    case proto::MessageType::done: done = c.expect<proto::Done>(*f); break;
                    case proto::MessageType::error: c.expect<proto::Ok>(*f); break;  // throws
                    default: break;
                }
            }
            if (dirty && Clock::now() - last_write >= interval) flush();
        }
        flush();
        if (!a.quiet) bar.finish();
        c.close();
        if (canvas.empty()) {
            std::fprintf(stderr, "omega: job %llu %s before any tile; no image written\n", (unsigned long long)job,
                         std::string(proto::to_string(done->state)).c_str());
        } else {
            std::printf("%s: %llu spp in %s (%s)\n", out.c_str(), (unsigned long long)done->progress.spp,
                        human_duration(done->progress.elapsed_s).c_str(), std::string(proto::to_string(done->state)).c_str());
        }
        return exit_for_end(done->state, job, done->message);
    });
}

}  // namespace omega::client
