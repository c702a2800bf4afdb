#include "submit_command.h"

#include <fmt/format.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "client_error.h"
#include "integrator/breakdown_collector.h"
#include "remote_common.h"

namespace omega::client {

namespace proto = omega::protocol;

namespace {

std::string read_asset(const ScannedAsset& a) {
    if (a.data) return *a.data;  // embedded in the scene file, held since the scan
    std::ifstream in(a.path, std::ios::binary);
    if (!in) throw ClientError(kExitBadInput, fmt::format("{}: cannot read", a.path));
    std::stringstream ss;
    ss << in.rdbuf();
    std::string bytes = ss.str();
    if (bytes.size() != a.size)
        throw ClientError(kExitBadInput, fmt::format("{}: changed while being submitted", a.path));
    return bytes;
}

}  // namespace

SubmitResult submit_scene(Connection& c, const ScannedScene& scene, const JobSpec& spec) {
    proto::Submit s;
    s.id = c.next_id();
    s.name = scene.name;
    s.priority = spec.priority;
    s.halt = spec.halt;
    s.seed = spec.seed;
    s.integrator = spec.integrator;
    s.sampler = spec.sampler;
    s.assets = scene.refs();
    s.scene = scene.yaml;
    s.workers = spec.workers;
    s.unit_spp = spec.unit_spp;

    SubmitResult result;
    proto::DecodedFrame reply = c.request(proto::encode(s), s.id);
    if (reply.type == proto::MessageType::need_assets) {
        const auto need = c.expect<proto::NeedAssets>(reply);
        std::map<std::string, const ScannedAsset*> by_hash;
        for (const auto& a : scene.assets) by_hash.emplace(a.sha256, &a);
        std::set<std::string> sent;
        for (const auto& h : need.missing) {
            auto it = by_hash.find(h);
            if (it == by_hash.end())
                throw ClientError(kExitInternal,
                                  fmt::format("{} asked for asset {}, which this scene does not use", c.address().text(), h));
            if (!sent.insert(h).second) continue;
            proto::Asset a;
            a.id = s.id;
            a.sha256 = h;
            a.data = read_asset(*it->second);
            if (sha256_bytes(a.data) != h)
                throw ClientError(kExitBadInput, fmt::format("{}: changed while being submitted", it->second->path));
            result.bytes_sent += a.data.size();
            c.send(proto::encode(a));
            ++result.assets_sent;
        }
        // The daemon may take a while to store large assets; wait as long as a reply may take.
        const auto deadline = Clock::now() + c.options().reply_timeout;
        for (;;) {
            reply = c.read(deadline);
            if (reply.id == s.id || (reply.id == 0 && reply.type == proto::MessageType::error)) break;
        }
    }
    result.job = c.expect<proto::Accepted>(reply).job;
    return result;
}

void add_submit_command(CLI::App& app, SubmitArgs& a) {
    auto* cmd = app.add_subcommand("submit", "Submit a scene to the render daemon; prints the job id last");
    cmd->add_option("scene", a.scene, "Scene file (YAML, format v1)")->required();
    add_host_option(cmd, a.host);
    cmd->add_option("--priority", a.priority, "Higher runs first, -1000..1000 (default 0)")
        ->check(CLI::Range(proto::kMinPriority, proto::kMaxPriority));
    auto* spp = cmd->add_option("--spp", a.spp, "Samples per pixel")->check(CLI::Range(uint64_t(1), uint64_t(1) << 40));
    auto* time = cmd->add_option("--time", a.time_s, "Render for this many seconds")->check(CLI::Range(1e-9, 1e9));
    auto* err = cmd->add_option("--target-error", a.target_error, "Stop at this estimated relative error")
                    ->check(CLI::Range(1e-12, 1e6));
    spp->excludes(time)->excludes(err);
    time->excludes(err);
    cmd->add_option("--seed", a.seed, "Random seed (default 0)");
    cmd->add_option("--integrator", a.integrator, "path | light | bdpt (overrides the scene)")
        ->check(CLI::IsMember({"path", "light", "bdpt"}));
    cmd->add_option("--sampler", a.sampler, "sobol | independent (overrides the scene's sampler)")
        ->check(CLI::IsMember({"sobol", "independent"}));
    cmd->add_option("--workers", a.workers,
                    "Render on `omega worker`s, at most N at once, in sample-range units (0: on the daemon; "
                    "default: the daemon's config)")
        ->check(CLI::Range(uint32_t(0), uint32_t(proto::kMaxWorkers)));
    cmd->add_option("--unit-spp", a.unit_spp, "Samples per work unit (default: sized to a few seconds each)")
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 40));
    cmd->add_flag("-q,--quiet", a.quiet, "Print only the job id");
    cmd->add_flag("--breakdown", a.breakdown,
                  "Ask for the path-class breakdown (the film key `breakdown`, set in the submitted scene): the "
                  "fetched image and the result carry omega.breakdown (docs/breakdown.md)");
    cmd->add_option("--breakdown-length", a.breakdown_length, "--breakdown: classes up to this many edges (default 6)")
        ->check(CLI::Range(1, kMaxBreakdownLength));
    cmd->add_option("--breakdown-box", a.breakdown_box, "--breakdown: measure the pixel box x0,y0,x1,y1");
}

namespace {

// The scene with its film's `breakdown` set: the job option travels in the scene, as `aov` does.
// Throws ClientError (bad input) for a malformed box.
std::string scene_with_breakdown(const std::string& yaml, const SubmitArgs& a) {
    YAML::Node root = YAML::Load(yaml);
    YAML::Node bd;
    bd["length"] = a.breakdown_length;
    if (!a.breakdown_box.empty()) {
        Rect b;
        try {
            b = parse_breakdown_box(a.breakdown_box);
        } catch (const std::invalid_argument& e) {
            throw ClientError(kExitBadInput, std::string("--breakdown-box: ") + e.what());
        }
        YAML::Node box;
        for (int v : {b.x0, b.y0, b.x1, b.y1}) box.push_back(v);
        box.SetStyle(YAML::EmitterStyle::Flow);
        bd["box"] = box;
    }
    bd.SetStyle(YAML::EmitterStyle::Flow);
    root["sensor"]["film"]["breakdown"] = bd;
    YAML::Emitter out;
    out << root;
    return std::string(out.c_str()) + "\n";
}

}  // namespace

int run_submit(const SubmitArgs& a) {
    return guarded([&] {
        ScannedScene scene = scan_scene(a.scene);
        if (a.breakdown || !a.breakdown_box.empty()) scene.yaml = scene_with_breakdown(scene.yaml, a);
        if (!a.quiet)
            for (const auto& w : scene.warnings) std::fprintf(stderr, "omega: warning: %s\n", w.c_str());
        JobSpec spec;
        spec.priority = a.priority;
        spec.halt = proto::Halt{a.spp, a.time_s, a.target_error};
        spec.seed = a.seed;
        if (!a.integrator.empty()) spec.integrator = a.integrator;
        if (!a.sampler.empty()) spec.sampler = a.sampler;
        spec.workers = a.workers;
        spec.unit_spp = a.unit_spp;
        Connection c = connect_to(a.host);
        SubmitResult r = submit_scene(c, scene, spec);
        c.close();
        if (!a.quiet)
            std::fprintf(stderr, "omega: submitted %s to %s: %zu asset(s), %zu sent (%s)\n", a.scene.c_str(),
                         c.address().text().c_str(), scene.assets.size(), r.assets_sent, human_bytes(r.bytes_sent).c_str());
        std::printf("%llu\n", (unsigned long long)r.job);
        std::fflush(stdout);
        return kExitOk;
    });
}

}  // namespace omega::client
