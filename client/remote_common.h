#pragma once
// Pieces every remote command shares: the --host option, connecting, error reporting, and
// formatting of job fields.
#include <CLI/CLI.hpp>

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "connection.h"
#include "protocol/messages.h"

namespace omega::client {

// Adds --host ADDR (default: docs/client.md, "Daemon address").
void add_host_option(CLI::App* cmd, std::optional<std::string>& host);

// Resolves the address and opens a session (throws ClientError).
Connection connect_to(const std::optional<std::string>& host, const ConnectOptions& opts = {});

// Runs body, printing a ClientError or any other exception as "omega: ..." on stderr and
// returning its exit code (1 for anything but a ClientError).
int guarded(const std::function<int()>& body);

std::string human_bytes(uint64_t n);
std::string human_duration(double seconds);
std::string format_halt(const protocol::Halt& h);
// "12/64 spp" or "12 spp", elapsed, error when known.
std::string format_progress(const protocol::ProgressInfo& p, const protocol::Halt& h);
// Fraction done for a progress bar, or -1 when unknown (time or error halts without spp).
double progress_fraction(const protocol::ProgressInfo& p, const protocol::Halt& h);

using protocol::is_terminal;

// Left-aligned columns separated by two spaces; the first row is the heading.
std::string format_table(const std::vector<std::vector<std::string>>& rows);

}  // namespace omega::client
