#pragma once
// `omega view --host ADDR --listen HOST:PORT`: the live job page (docs/web.md). A loopback-only
// bridge between a browser and omegad: it serves the static page (client/web/) and, for each
// WebSocket, opens its own protocol sessions to omegad as the user who logged in on the page, so
// omegad's users, tokens, owners, admins and limits apply unchanged. HTTP and WebSocket framing
// are civetweb's (Debian's libcivetweb).
#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace omega::client {

struct ViewArgs {
    std::optional<std::string> host;
    std::string listen = "127.0.0.1:7180";
    std::string web_root;  // default: the page in the source tree (OMEGA_WEB_ROOT)
    double list_interval_s = 1.0;
};

void add_view_command(CLI::App& app, ViewArgs& args);
// Serves until SIGINT or SIGTERM. Called on the main thread.
int run_view(const ViewArgs& args);

}  // namespace omega::client
