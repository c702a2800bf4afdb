#pragma once
// omegad's configuration: a YAML file (docs/daemon.md lists every key) overridden by the command
// line. Loaded at start-up and again on SIGHUP (listeners and state_dir only take effect at start).
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "daemon/log.h"
#include "daemon/slurm_executor.h"

namespace omega::daemon {

struct Config {
  std::vector<std::string> listen;  // "unix:/path" or "tcp:host:port"
  std::string state_dir = "/var/lib/omega";
  int threads = 0;                  // render workers; 0 = all cores
  int max_running = 1;              // jobs rendering at once
  double checkpoint_interval_s = 30;  // at most one checkpoint per job this often (0 = every pass)
  double drain_timeout_s = 30;      // SIGTERM: how long running jobs get to reach a pass boundary
  std::vector<std::string> allowed_roots;  // absolute dirs a scene may read besides its own assets
  LogLevel log_level = LogLevel::info;
  int tile_size = 32;
  // Limits.
  std::uint64_t max_header_bytes = 1u << 20;
  std::uint64_t max_submit_bytes = 64ull << 20;
  std::uint64_t max_asset_bytes = 1ull << 30;
  std::uint64_t output_buffer_bytes = 256ull << 20;  // per client, besides coalesced tiles
  int max_connections = 1024;
  int max_pending_submits = 4;  // per connection
  int max_queued_jobs = 10000;
  std::uint64_t max_asset_cache_bytes = 16ull << 30;  // LRU eviction of assets no job needs
  int max_jobs_per_owner = 1000;       // unfinished jobs of one owner (`busy` beyond)
  int max_resolution = 16384;          // film width and height, each
  std::uint64_t max_spp = 1ull << 24;  // a job's spp halt (and the default when it has none)
  double max_time_s = 7 * 86400.0;     // a job's time halt
  std::uint64_t max_scene_memory_bytes = 8ull << 30;  // estimated memory of a built scene + film
  double frame_timeout_s = 30;         // a frame begun must be complete within this (0: never)
  double handshake_timeout_s = 10;     // hello (and auth on TCP) must be done within this
  // Failed TCP authentications one source address may make in a sliding minute; beyond it every
  // auth from that address is refused (auth_failed, the token unchecked) until the oldest
  // failure is a minute old. 0: no limit.
  int auth_fail_limit = 10;
  // Access. TCP users and their tokens (shared secrets for the HMAC handshake); empty = TCP
  // without authentication (owner "tcp"), which is allowed only on loopback listeners.
  std::map<std::string, std::string> tcp_users;  // user -> token
  // TCP users whose role is `worker` (tcp_users: NAME: {token: T, role: worker}): they may only
  // take work units and the assets of those units (omega worker), never submit or control jobs.
  std::set<std::string> worker_users;
  // Work units (docs/farm.md "Workers"): a submit without `workers` gets this many (0: jobs render
  // on the daemon's own threads), and units are sized to take about unit_seconds on a worker.
  int workers = 0;
  double unit_seconds = 4;
  // Who starts the workers of a worker job: `local` (nobody: started by hand or by systemd) or
  // `slurm` (omegad submits them with sbatch; docs/farm.md "Workers under Slurm").
  std::string executor = "local";
  SlurmSettings slurm;
  std::vector<std::string> admins;  // identities that may act on any job: uids (unix) or TCP user names
  std::string tls_cert, tls_key;  // PEM files: when both are set, every TCP listener speaks TLS
};

// Throws std::runtime_error "FILE: key: what" for an unreadable file, an unknown key or a bad
// value. An empty path gives the defaults.
Config load_config(const std::string& path);

// A TCP user name the config may define: non-empty, printable, not all digits (those are unix
// uids) and not "tcp" (the anonymous loopback identity).
bool valid_tcp_user_name(const std::string& name);

// Checks a whole config (after command-line overrides). Throws std::runtime_error.
void validate_config(const Config& c);

}  // namespace omega::daemon
