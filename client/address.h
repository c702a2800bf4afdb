#pragma once
// Daemon addresses: `unix:/path`, `tcp:host:port` or `tls:host:port` (docs/client.md).
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace omega::client {

struct Address {
    enum class Kind { unix_socket, tcp };
    Kind kind = Kind::unix_socket;
    std::string path;  // unix
    std::string host;  // tcp (a name, an IPv4 address, or an IPv6 address in brackets or bare)
    uint16_t port = 0;  // tcp
    bool tls = false;   // tcp: `tls:host:port`, TCP wrapped in TLS (the daemon's tls_cert)
    std::string text() const;  // as the user writes it
};

// Throws ClientError (exit 2) naming the text when it is not a valid address.
Address parse_address(const std::string& text);

// The default address: $OMEGA_HOST, then $XDG_RUNTIME_DIR/omega/omegad.sock when that socket
// exists, then /run/omega/omegad.sock. getenv is injectable for tests; exists checks a path.
std::string default_address_text(const std::function<const char*(const char*)>& getenv_fn,
                                 const std::function<bool(const std::string&)>& exists_fn);
std::string default_address_text();

// --host when given, else the default.
Address resolve_address(const std::optional<std::string>& host_flag);

}  // namespace omega::client
