#include "daemon/config.h"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>

namespace omega::daemon {

namespace {

struct Reader {
  const std::string& file;
  const YAML::Node& root;
  std::set<std::string> seen;

  [[noreturn]] void fail(const std::string& key, const YAML::Mark& m, const std::string& what) const {
    throw std::runtime_error(file + ":" + std::to_string(m.line + 1) + ": " + key + ": " + what);
  }
  YAML::Node get(const std::string& key) {
    seen.insert(key);
    return root[key];
  }
  // Refuses a key given twice in `map`: yaml-cpp keeps both and a lookup reads the first, so an
  // override appended to the file was ignored without a word. Which one was meant is not for
  // omegad to guess.
  void unique_keys(const YAML::Node& map, const std::string& prefix) const {
    std::map<std::string, int> first_line;
    for (const auto& kv : map) {
      const std::string k = kv.first.as<std::string>();
      const auto [it, fresh] = first_line.emplace(k, kv.first.Mark().line + 1);
      if (!fresh) fail(prefix + k, kv.first.Mark(), "given twice (first at line " + std::to_string(it->second) + ")");
    }
  }
  template <class T>
  void scalar(const std::string& key, T& out) {
    YAML::Node n = get(key);
    if (!n) return;
    if (!n.IsScalar()) fail(key, n.Mark(), "expected a scalar");
    try {
      out = n.as<T>();
    } catch (const YAML::Exception&) {
      fail(key, n.Mark(), "cannot read '" + n.Scalar() + "'");
    }
  }
  void strings(const std::string& key, std::vector<std::string>& out) {
    YAML::Node n = get(key);
    if (!n) return;
    if (!n.IsSequence()) fail(key, n.Mark(), "expected a list of strings");
    out.clear();
    for (const auto& item : n) {
      if (!item.IsScalar()) fail(key, item.Mark(), "expected a string");
      out.push_back(item.Scalar());
    }
  }
};

}  // namespace

Config load_config(const std::string& path) {
  Config c;
  if (path.empty()) return c;
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw std::runtime_error(path + ": cannot read the config file");
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (root.IsNull()) return c;
  if (!root.IsMap()) throw std::runtime_error(path + ":1: the config must be a mapping");
  Reader r{path, root, {}};
  r.unique_keys(root, "");
  r.strings("listen", c.listen);
  r.scalar("state_dir", c.state_dir);
  r.scalar("threads", c.threads);
  r.scalar("workers", c.workers);
  r.scalar("unit_seconds", c.unit_seconds);
  r.scalar("executor", c.executor);
  if (YAML::Node sl = r.get("slurm")) {
    if (!sl.IsMap()) r.fail("slurm", sl.Mark(), "expected a mapping");
    r.unique_keys(sl, "slurm.");
    for (const auto& kv : sl) {
      const std::string k = kv.first.as<std::string>();
      const YAML::Node v = kv.second;
      auto str = [&](std::string& out) {
        if (!v.IsScalar()) r.fail("slurm." + k, v.Mark(), "expected a string");
        else out = v.Scalar();
      };
      auto num = [&](auto& out) {
        try {
          out = v.as<std::decay_t<decltype(out)>>();
        } catch (const std::exception&) {
          r.fail("slurm." + k, v.Mark(), "expected a number");
        }
      };
      if (k == "omega") str(c.slurm.omega);
      else if (k == "connect") str(c.slurm.connect);
      else if (k == "user") str(c.slurm.user);
      else if (k == "token_file") str(c.slurm.token_file);
      else if (k == "partition") str(c.slurm.partition);
      else if (k == "time_limit") str(c.slurm.time_limit);
      else if (k == "threads") num(c.slurm.threads);
      else if (k == "poll_s") num(c.slurm.poll_s);
      else if (k == "idle_exit_s") num(c.slurm.idle_exit_s);
      else if (k == "max_replacements") num(c.slurm.max_replacements);
      else if (k == "sbatch_options") {
        if (!v.IsSequence()) r.fail("slurm.sbatch_options", v.Mark(), "expected a list of strings");
        else
          for (const auto& o : v) c.slurm.sbatch_options.push_back(o.as<std::string>());
      } else {
        r.fail("slurm." + k, kv.first.Mark(), "unknown key");
      }
    }
  }
  r.scalar("max_running", c.max_running);
  r.scalar("checkpoint_interval_s", c.checkpoint_interval_s);
  r.scalar("drain_timeout_s", c.drain_timeout_s);
  r.strings("allowed_roots", c.allowed_roots);
  std::string level;
  r.scalar("log_level", level);
  if (!level.empty()) {
    try {
      c.log_level = parse_log_level(level);
    } catch (const std::invalid_argument& e) {
      r.fail("log_level", root["log_level"].Mark(), e.what());
    }
  }
  r.scalar("tile_size", c.tile_size);
  r.scalar("max_header_bytes", c.max_header_bytes);
  r.scalar("max_submit_bytes", c.max_submit_bytes);
  r.scalar("max_asset_bytes", c.max_asset_bytes);
  r.scalar("output_buffer_bytes", c.output_buffer_bytes);
  r.scalar("max_connections", c.max_connections);
  r.scalar("max_pending_submits", c.max_pending_submits);
  r.scalar("max_queued_jobs", c.max_queued_jobs);
  r.scalar("max_asset_cache_bytes", c.max_asset_cache_bytes);
  r.scalar("max_jobs_per_owner", c.max_jobs_per_owner);
  r.scalar("max_resolution", c.max_resolution);
  r.scalar("max_spp", c.max_spp);
  r.scalar("max_time_s", c.max_time_s);
  r.scalar("max_scene_memory_bytes", c.max_scene_memory_bytes);
  r.scalar("frame_timeout_s", c.frame_timeout_s);
  r.scalar("handshake_timeout_s", c.handshake_timeout_s);
  r.scalar("auth_fail_limit", c.auth_fail_limit);
  r.strings("admins", c.admins);
  r.scalar("tls_cert", c.tls_cert);
  r.scalar("tls_key", c.tls_key);
  if (YAML::Node users = r.get("tcp_users")) {
    // user: TOKEN  or  user: {token: T | token_file: PATH, role: user | worker}
    if (!users.IsMap()) r.fail("tcp_users", users.Mark(), "expected a mapping of user to token");
    r.unique_keys(users, "tcp_users.");
    for (const auto& kv : users) {
      const std::string user = kv.first.as<std::string>();
      std::string token;
      const YAML::Node v = kv.second;
      auto known = [&](const YAML::Node& m) {
        for (const auto& e : m) {
          const std::string k = e.first.as<std::string>();
          if (k != "token" && k != "token_file" && k != "role") return false;
        }
        return true;
      };
      if (v.IsScalar()) {
        token = v.Scalar();
      } else if (v.IsMap() && known(v) && (v["token"] ? 1 : 0) + (v["token_file"] ? 1 : 0) == 1 &&
                 (v["token"] ? v["token"].IsScalar() : v["token_file"].IsScalar())) {
        if (v["token"]) {
          token = v["token"].Scalar();
        } else {
          const std::string file = v["token_file"].Scalar();
          std::ifstream in(file);
          if (!in) r.fail("tcp_users." + user, v.Mark(), "cannot read the token file '" + file + "'");
          std::getline(in, token);
        }
        if (const YAML::Node role = v["role"]) {
          if (!role.IsScalar() || (role.Scalar() != "user" && role.Scalar() != "worker"))
            r.fail("tcp_users." + user + ".role", role.Mark(), "expected user or worker");
          else if (role.Scalar() == "worker")
            c.worker_users.insert(user);
        }
      } else {
        r.fail("tcp_users." + user, v.Mark(), "expected a token or {token: T | token_file: PATH, role: user|worker}");
      }
      if (!valid_tcp_user_name(user))
        r.fail("tcp_users." + user, kv.first.Mark(), "a TCP user name must be printable, not all digits and not 'tcp'");
      if (token.size() < 16) r.fail("tcp_users." + user, kv.second.Mark(), "the token must be at least 16 bytes");
      c.tcp_users[user] = token;
    }
  }
  for (const auto& kv : root) {
    std::string key = kv.first.as<std::string>();
    if (!r.seen.count(key)) r.fail(key, kv.first.Mark(), "unknown key");
  }
  validate_config(c);
  return c;
}

bool valid_tcp_user_name(const std::string& name) {
  if (name.empty() || name.size() > 256 || name == "tcp") return false;
  if (name.find_first_not_of("0123456789") == std::string::npos) return false;
  for (unsigned char ch : name)
    if (ch < 0x21 || ch == 0x7f) return false;
  return true;
}

void validate_config(const Config& c) {
  auto bad = [](const std::string& what) { throw std::runtime_error("config: " + what); };
  if (c.state_dir.empty()) bad("state_dir: must not be empty");
  if (c.threads < 0) bad("threads: must be >= 0");
  if (c.max_running < 1) bad("max_running: must be >= 1");
  if (c.checkpoint_interval_s < 0) bad("checkpoint_interval_s: must be >= 0");
  if (c.drain_timeout_s < 0) bad("drain_timeout_s: must be >= 0");
  if (c.tile_size < 4 || c.tile_size > 1024) bad("tile_size: must be in [4, 1024]");
  if (c.max_header_bytes < 1024 || c.max_header_bytes > (1u << 30)) bad("max_header_bytes: must be in [1 KiB, 1 GiB]");
  if (c.max_connections < 1) bad("max_connections: must be >= 1");
  if (c.max_pending_submits < 1) bad("max_pending_submits: must be >= 1");
  if (c.output_buffer_bytes < (1u << 16)) bad("output_buffer_bytes: must be >= 64 KiB");
  if (c.tls_cert.empty() != c.tls_key.empty()) bad("tls_cert and tls_key: give both or neither");
  if (c.max_jobs_per_owner < 1) bad("max_jobs_per_owner: must be >= 1");
  if (c.max_resolution < 1) bad("max_resolution: must be >= 1");
  if (c.max_spp < 1) bad("max_spp: must be >= 1");
  if (!(c.max_time_s > 0)) bad("max_time_s: must be > 0");
  if (c.frame_timeout_s < 0) bad("frame_timeout_s: must be >= 0");
  if (!(c.handshake_timeout_s > 0)) bad("handshake_timeout_s: must be > 0");
  if (c.auth_fail_limit < 0) bad("auth_fail_limit: must be >= 0 (0: no limit)");
  if (c.workers < 0 || c.workers > 100000) bad("workers: must be in [0, 100000] (0: jobs render on the daemon)");
  if (!(c.unit_seconds > 0)) bad("unit_seconds: must be > 0");
  if (c.executor != "local" && c.executor != "slurm") bad("executor: must be local or slurm");
  if (c.executor == "slurm") {
    if (c.slurm.connect.empty()) bad("slurm.connect: the address workers connect back to (tcp:HOST:PORT) is required");
    if (c.slurm.user.empty() || !c.worker_users.count(c.slurm.user))
      bad("slurm.user: must name a tcp_users entry with role: worker");
    if (c.slurm.token_file.empty()) bad("slurm.token_file: the worker token's file (0600, on the nodes) is required");
    if (c.slurm.threads < 0) bad("slurm.threads: must be >= 0");
    if (!(c.slurm.poll_s >= 1)) bad("slurm.poll_s: must be >= 1");
    if (!(c.slurm.idle_exit_s > 0)) bad("slurm.idle_exit_s: must be > 0");
    if (c.slurm.max_replacements < 0) bad("slurm.max_replacements: must be >= 0");
  }
  for (const auto& [user, token] : c.tcp_users)
    if (!valid_tcp_user_name(user)) bad("tcp_users: '" + user + "' is not a valid TCP user name");
  for (const auto& r : c.allowed_roots) {
    if (!std::filesystem::path(r).is_absolute()) bad("allowed_roots: '" + r + "' is not an absolute path");
    // A root that holds the state directory (or lies in it) would let a scene read other jobs'
    // scenes, results, checkpoints and the asset cache.
    std::error_code ec;
    const auto canon = [&](const std::string& p) {
      std::filesystem::path a = std::filesystem::weakly_canonical(std::filesystem::absolute(p, ec), ec);
      std::string s = a.lexically_normal().string();
      while (s.size() > 1 && s.back() == '/') s.pop_back();
      return s;
    };
    const std::string root = canon(r), state = canon(c.state_dir);
    const auto under = [](const std::string& a, const std::string& b) {  // a is b or beneath it
      return a == b || b == "/" || (a.size() > b.size() && a.compare(0, b.size(), b) == 0 && a[b.size()] == '/');
    };
    if (under(state, root) || under(root, state))
      bad("allowed_roots: '" + r + "' overlaps the state directory '" + c.state_dir +
          "' (a scene could read other jobs' files); name folders outside it");
  }
}

}  // namespace omega::daemon
