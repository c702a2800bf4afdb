// `omega view`: serves the job page (client/web/) and its WebSocket with civetweb.
//
// Threads: civetweb's model, a fixed pool of worker threads (num_threads), each serving one
// connection at a time; a WebSocket keeps its worker for as long as it is open, so the pool bounds
// the open pages. Each WebSocket also has one ViewSession thread (view_session.h) that talks to
// omegad. This is a per-user bridge process on loopback; omegad itself keeps its single epoll
// loop and gains no listener.
#include "view_command.h"

#include <civetweb.h>
#include <fmt/format.h>
#include <openssl/rand.h>
#include <signal.h>

#include <cstdio>
#include <filesystem>
#include <mutex>

#include "remote_common.h"
#include "view_messages.h"
#include "view_session.h"

#ifndef OMEGA_WEB_ROOT
#define OMEGA_WEB_ROOT "client/web"
#endif

namespace omega::client {

namespace {

constexpr int kWorkers = 24;  // civetweb workers: open pages plus static-file requests

struct Server {
    ViewSessionConfig cfg;
};

// "HOST:PORT" or "[V6]:PORT" -> (HOST, PORT); nullopt when malformed.
std::optional<std::pair<std::string, int>> split_host_port(const std::string& s) {
    const auto colon = s.rfind(':');
    if (colon == std::string::npos || colon == 0) return std::nullopt;
    std::string host = s.substr(0, colon);
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
    const std::string port = s.substr(colon + 1);
    if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
    const int p = std::stoi(port);
    if (p > 65535) return std::nullopt;
    return std::pair{host, p};
}

// Civetweb worker (WebSocket upgrade request): the DNS-rebinding and cross-site checks of
// websocket_upgrade_allowed (view_messages.h). Returns 0 to accept, 1 to refuse (civetweb's
// convention).
int on_ws_connect(const mg_connection* c, void*) {
    return websocket_upgrade_allowed(mg_get_header(c, "Host"), mg_get_header(c, "Origin")) ? 0 : 1;
}

// Civetweb worker of the new WebSocket: starts its session. No lock: the connection is this
// worker's alone until ready returns.
void on_ws_ready(mg_connection* c, void* cb) {
    auto* srv = static_cast<Server*>(cb);
    auto send = [c](const std::string& data, bool binary) {
        const int op = binary ? MG_WEBSOCKET_OPCODE_BINARY : MG_WEBSOCKET_OPCODE_TEXT;
        return mg_websocket_write(c, op, data.data(), data.size()) > 0;  // locks the connection itself
    };
    auto close = [c] { mg_websocket_write(c, MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE, "", 0); };
    mg_set_user_connection_data(c, new ViewSession(srv->cfg, send, close));
}

// Civetweb worker of the WebSocket, one message (unfragmented frame) at a time. Returns 1 to
// keep the WebSocket, 0 to close it.
int on_ws_data(mg_connection* c, int bits, char* data, size_t len, void*) {
    auto* s = static_cast<ViewSession*>(mg_get_user_connection_data(c));
    switch (bits & 0x0f) {
        case MG_WEBSOCKET_OPCODE_TEXT: return s && s->push(std::string(data, len)) ? 1 : 0;
        case MG_WEBSOCKET_OPCODE_PING:
        case MG_WEBSOCKET_OPCODE_PONG: return 1;
        default: return 0;  // close, binary, or a fragment: the page never sends these
    }
}

// Civetweb worker of the WebSocket, once it closed: stops and joins its session thread.
void on_ws_close(const mg_connection* c, void*) {
    delete static_cast<ViewSession*>(mg_get_user_connection_data(c));
    mg_set_user_connection_data(c, nullptr);
}

std::string random_key() {
    unsigned char b[16];
    if (RAND_bytes(b, sizeof b) != 1) throw ClientError(kExitInternal, "no random bytes for the access key");
    std::string out;
    for (unsigned char x : b) out += fmt::format("{:02x}", x);
    return out;
}

}  // namespace

void add_view_command(CLI::App& app, ViewArgs& a) {
    auto* cmd = app.add_subcommand("view", "Serve the live job page to a browser on this machine (docs/web.md)");
    add_host_option(cmd, a.host);
    cmd->add_option("--listen", a.listen, "Loopback HOST:PORT to serve on (default 127.0.0.1:7180; port 0 picks one)");
    cmd->add_option("--web-root", a.web_root, "Folder of the page's static files (default: the source tree's client/web)");
    cmd->add_option("--list-interval", a.list_interval_s, "Seconds between job-list refreshes (default 1)")
        ->check(CLI::Range(0.1, 3600.0));
}

int run_view(const ViewArgs& a) {
    return guarded([&] {
        auto hp = split_host_port(a.listen);
        if (!hp) throw ClientError(kExitBadInput, fmt::format("--listen '{}': expected HOST:PORT", a.listen));
        if (!is_loopback_host(hp->first))
            throw ClientError(kExitBadInput, fmt::format("--listen '{}': omega view serves loopback only (127.0.0.0/8, ::1, localhost)", a.listen));
        const std::string root = a.web_root.empty() ? std::string(OMEGA_WEB_ROOT) : a.web_root;
        if (!std::filesystem::is_regular_file(std::filesystem::path(root) / "index.html"))
            throw ClientError(kExitBadInput, fmt::format("--web-root '{}': no index.html there", root));

        Server srv;
        srv.cfg.daemon = resolve_address(a.host);
        srv.cfg.access_key = random_key();
        srv.cfg.list_interval_s = a.list_interval_s;

        mg_init_library(0);
        if (!mg_check_feature(MG_FEATURES_WEBSOCKET)) throw ClientError(kExitInternal, "this civetweb lacks WebSocket support");
        // Signals are taken by sigwait below; every thread started from here inherits the mask.
        sigset_t sigs;
        sigemptyset(&sigs);
        sigaddset(&sigs, SIGINT);
        sigaddset(&sigs, SIGTERM);
        sigaddset(&sigs, SIGPIPE);
        pthread_sigmask(SIG_BLOCK, &sigs, nullptr);

        const std::string listen = hp->first.find(':') != std::string::npos
                                       ? fmt::format("[{}]:{}", hp->first, hp->second)
                                       : fmt::format("{}:{}", hp->first == "localhost" ? "127.0.0.1" : hp->first, hp->second);
        const std::string workers = std::to_string(kWorkers);
        const char* options[] = {"listening_ports", listen.c_str(), "document_root", root.c_str(),
                                 "num_threads", workers.c_str(), "enable_directory_listing", "no",
                                 "enable_websocket_ping_pong", "yes", "websocket_timeout_ms", "20000",
                                 "additional_header", "X-Content-Type-Options: nosniff", nullptr};
        mg_callbacks cb{};
        mg_context* ctx = mg_start(&cb, &srv, options);
        if (!ctx) throw ClientError(kExitUnreachable, fmt::format("cannot serve on {} (in use?)", a.listen));
        mg_set_websocket_handler(ctx, "/ws", on_ws_connect, on_ws_ready, on_ws_data, on_ws_close, &srv);
        mg_server_port ports[4]{};
        const int n = mg_get_server_ports(ctx, 4, ports);
        const int port = n > 0 ? ports[0].port : hp->second;
        const std::string shown = hp->first.find(':') != std::string::npos ? "[" + hp->first + "]" : hp->first;
        std::printf("omega view: serving http://%s:%d/ for the daemon at %s\n", shown.c_str(), port,
                    srv.cfg.daemon.text().c_str());
        std::printf("omega view: where the daemon has no TCP users (a unix socket, or loopback TCP without "
                    "tcp_users), log in with the access key: http://%s:%d/#key=%s\n",
                    shown.c_str(), port, srv.cfg.access_key.c_str());
        std::fflush(stdout);
        int sig = 0;
        while (sig != SIGINT && sig != SIGTERM) sigwait(&sigs, &sig);
        mg_stop(ctx);  // closes every WebSocket: each close handler joins its session
        std::printf("omega view: stopped\n");
        return kExitOk;
    });
}

}  // namespace omega::client
