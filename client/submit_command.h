#pragma once
// `omega submit SCENE`: sends a scene and its assets to omegad, prints the job id last.
#include <CLI/CLI.hpp>

#include <optional>
#include <string>

#include "asset_scan.h"
#include "connection.h"

namespace omega::client {

struct JobSpec {  // what a submit asks for, beside the scene
    int64_t priority = 0;
    protocol::Halt halt;  // empty: the scene's own
    uint64_t seed = 0;
    std::optional<std::string> integrator;
    std::optional<std::string> sampler;  // sobol | independent; none: the scene's
    std::optional<uint32_t> workers;     // render on omega workers (docs/farm.md "Workers")
    std::optional<uint64_t> unit_spp;
};

struct SubmitResult {
    uint64_t job = 0;
    size_t assets_sent = 0;
    uint64_t bytes_sent = 0;
};

// The submit exchange: submit, need_assets, one asset frame per missing hash, accepted.
// Throws ClientError (the daemon's refusal mapped by error_to_exception).
SubmitResult submit_scene(Connection& c, const ScannedScene& scene, const JobSpec& spec);

struct SubmitArgs {
    std::string scene;
    std::optional<std::string> host;
    int64_t priority = 0;
    std::optional<uint64_t> spp;
    std::optional<double> time_s;
    std::optional<double> target_error;
    uint64_t seed = 0;
    std::string integrator;
    std::string sampler;
    std::optional<uint32_t> workers;
    std::optional<uint64_t> unit_spp;
    bool quiet = false;
    // --breakdown: sets the film key `breakdown` of the submitted scene (docs/breakdown.md).
    bool breakdown = false;
    int breakdown_length = 6;
    std::string breakdown_box;
};

void add_submit_command(CLI::App& app, SubmitArgs& args);
int run_submit(const SubmitArgs& args);

}  // namespace omega::client
