#include "address.h"

#include <fmt/format.h>
#include <sys/stat.h>

#include <charconv>
#include <cstdlib>

#include "client_error.h"

namespace omega::client {

std::string Address::text() const {
    if (kind == Kind::unix_socket) return "unix:" + path;
    const char* scheme = tls ? "tls" : "tcp";
    if (host.find(':') != std::string::npos) return fmt::format("{}:[{}]:{}", scheme, host, port);
    return fmt::format("{}:{}:{}", scheme, host, port);
}

Address parse_address(const std::string& text) {
    auto bad = [&](const std::string& why) {
        return ClientError(kExitBadInput,
                           fmt::format("bad daemon address '{}': {} (expected unix:/path, tcp:host:port or tls:host:port)", text, why));
    };
    Address a;
    if (text.rfind("unix:", 0) == 0) {
        a.kind = Address::Kind::unix_socket;
        a.path = text.substr(5);
        if (a.path.empty()) throw bad("empty socket path");
        if (a.path.find('\0') != std::string::npos) throw bad("NUL in socket path");
        if (a.path.size() >= 108) throw bad("socket path longer than 107 bytes");
        return a;
    }
    if (text.rfind("tcp:", 0) == 0 || text.rfind("tls:", 0) == 0) {
        a.kind = Address::Kind::tcp;
        a.tls = text[1] == 'l';
        std::string rest = text.substr(4);
        std::string port;
        if (!rest.empty() && rest[0] == '[') {
            const size_t close = rest.find(']');
            if (close == std::string::npos || close + 1 >= rest.size() || rest[close + 1] != ':')
                throw bad("an IPv6 address is written [addr]:port");
            a.host = rest.substr(1, close - 1);
            port = rest.substr(close + 2);
        } else {
            const size_t colon = rest.rfind(':');
            if (colon == std::string::npos) throw bad("missing port");
            a.host = rest.substr(0, colon);
            port = rest.substr(colon + 1);
            if (a.host.find(':') != std::string::npos) throw bad("an IPv6 address is written [addr]:port");
        }
        if (a.host.empty()) throw bad("empty host");
        unsigned v = 0;
        auto [p, ec] = std::from_chars(port.data(), port.data() + port.size(), v);
        if (port.empty() || ec != std::errc() || p != port.data() + port.size() || v == 0 || v > 65535)
            throw bad("port must be a number in 1..65535");
        a.port = uint16_t(v);
        return a;
    }
    throw bad("unknown scheme");
}

std::string default_address_text(const std::function<const char*(const char*)>& getenv_fn,
                                 const std::function<bool(const std::string&)>& exists_fn) {
    if (const char* h = getenv_fn("OMEGA_HOST"); h && *h) return h;
    if (const char* r = getenv_fn("XDG_RUNTIME_DIR"); r && *r) {
        std::string p = std::string(r) + "/omega/omegad.sock";
        if (exists_fn(p)) return "unix:" + p;
    }
    return "unix:/run/omega/omegad.sock";
}

std::string default_address_text() {
    return default_address_text([](const char* n) { return std::getenv(n); },
                                [](const std::string& p) {
                                    struct stat st{};
                                    return ::stat(p.c_str(), &st) == 0;
                                });
}

Address resolve_address(const std::optional<std::string>& host_flag) {
    return parse_address(host_flag ? *host_flag : default_address_text());
}

}  // namespace omega::client
