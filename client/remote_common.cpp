#include "remote_common.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>

namespace omega::client {

void add_host_option(CLI::App* cmd, std::optional<std::string>& host) {
    cmd->add_option("--host", host,
                    "Daemon address, unix:/path or tcp:host:port (default: $OMEGA_HOST, then "
                    "$XDG_RUNTIME_DIR/omega/omegad.sock, then /run/omega/omegad.sock)");
}

Connection connect_to(const std::optional<std::string>& host, const ConnectOptions& opts) {
    return Connection::open(resolve_address(host), opts);
}

int guarded(const std::function<int()>& body) {
    try {
        return body();
    } catch (const ClientError& e) {
        std::fprintf(stderr, "omega: %s\n", e.what());
        return e.exit_code();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "omega: internal error: %s\n", e.what());
        return kExitInternal;
    }
}

std::string human_bytes(uint64_t n) {
    if (n >= (1ull << 30)) return fmt::format("{:.1f} GiB", double(n) / double(1ull << 30));
    if (n >= (1ull << 20)) return fmt::format("{:.1f} MiB", double(n) / double(1ull << 20));
    if (n >= (1ull << 10)) return fmt::format("{:.1f} KiB", double(n) / double(1ull << 10));
    return fmt::format("{} B", n);
}

std::string human_duration(double s) {
    if (s < 60) return fmt::format("{:.1f}s", s);
    const long long t = (long long)s;
    if (t < 3600) return fmt::format("{}m{:02}s", t / 60, t % 60);
    return fmt::format("{}h{:02}m", t / 3600, (t / 60) % 60);
}

std::string format_halt(const protocol::Halt& h) {
    std::vector<std::string> parts;
    if (h.spp) parts.push_back(fmt::format("{} spp", *h.spp));
    if (h.time_s) parts.push_back(fmt::format("{}s", *h.time_s));
    if (h.target_error) parts.push_back(fmt::format("error {}", *h.target_error));
    if (parts.empty()) return "scene";
    std::string out = parts[0];
    for (size_t i = 1; i < parts.size(); ++i) out += " | " + parts[i];
    return out;
}

std::string format_progress(const protocol::ProgressInfo& p, const protocol::Halt& h) {
    std::string s = h.spp ? fmt::format("{}/{} spp", p.spp, *h.spp) : fmt::format("{} spp", p.spp);
    s += "  " + human_duration(p.elapsed_s);
    if (p.rel_error) s += fmt::format("  err {:.4f}", *p.rel_error);
    return s;
}

double progress_fraction(const protocol::ProgressInfo& p, const protocol::Halt& h) {
    double f = -1;
    if (h.spp && *h.spp > 0) f = double(p.spp) / double(*h.spp);
    if (h.time_s && *h.time_s > 0) f = std::max(f, p.elapsed_s / *h.time_s);
    return f < 0 ? -1 : std::min(f, 1.0);
}

std::string format_table(const std::vector<std::vector<std::string>>& rows) {
    std::vector<size_t> w;
    for (const auto& r : rows)
        for (size_t i = 0; i < r.size(); ++i) {
            if (w.size() <= i) w.push_back(0);
            w[i] = std::max(w[i], r[i].size());
        }
    std::string out;
    for (const auto& r : rows) {
        std::string line;
        for (size_t i = 0; i < r.size(); ++i) {
            line += r[i];
            if (i + 1 < r.size()) line += std::string(w[i] - r[i].size() + 2, ' ');
        }
        out += line + "\n";
    }
    return out;
}

}  // namespace omega::client
