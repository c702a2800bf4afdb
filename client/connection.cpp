#include "connection.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <openssl/evp.h>
#include <openssl/err.h>
#include <openssl/hmac.h>
#include <openssl/ssl.h>
#include <openssl/x509v3.h>
#include <poll.h>
#include <pwd.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>

namespace omega::client {

namespace proto = omega::protocol;

// ---------------------------------------------------------------- FrameSocket

FrameSocket::FrameSocket(int fd, proto::DecoderLimits limits) : fd_(fd), decoder_(limits) {}
FrameSocket::~FrameSocket() { close(); }
FrameSocket::FrameSocket(FrameSocket&& o) noexcept
    : fd_(o.fd_), ssl_(std::move(o.ssl_)), decoder_(std::move(o.decoder_)), pending_(std::move(o.pending_)), error_(std::move(o.error_)) {
    o.fd_ = -1;
}
FrameSocket& FrameSocket::operator=(FrameSocket&& o) noexcept {
    if (this != &o) {
        close();
        fd_ = o.fd_;
        o.fd_ = -1;
        ssl_ = std::move(o.ssl_);
        decoder_ = std::move(o.decoder_);
        pending_ = std::move(o.pending_);
        error_ = std::move(o.error_);
    }
    return *this;
}

void FrameSocket::close() {
    ssl_.reset();
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
}

void FrameSocket::send(const proto::Frame& f) {
    if (fd_ < 0) throw std::runtime_error("connection closed");
    const std::string bytes = proto::encode_frame(f);
    size_t done = 0;
    while (done < bytes.size()) {
        if (ssl_) {
            const int n = SSL_write(ssl_.get(), bytes.data() + done, int(std::min<size_t>(bytes.size() - done, 1 << 30)));
            if (n <= 0) throw std::runtime_error("TLS write failed");
            done += size_t(n);
            continue;
        }
        const ssize_t n = ::send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
        if (n < 0) {
            if (errno == EINTR) continue;
            throw std::runtime_error(std::string("send: ") + std::strerror(errno));
        }
        done += size_t(n);
    }
}

FrameSocket::ReadStatus FrameSocket::read(Clock::time_point deadline, proto::DecodedFrame& out) {
    for (;;) {
        // Bytes left over from an earlier read go in first (the decoder pauses when frames queue).
        if (!pending_.empty() && !decoder_.failed()) {
            const size_t took = decoder_.feed(std::string_view(pending_));
            pending_.erase(0, took);
        }
        if (auto f = decoder_.next()) {
            out = std::move(*f);
            return ReadStatus::frame;
        }
        if (decoder_.failed()) {
            error_ = std::string(proto::to_string(decoder_.error()->code)) + ": " + decoder_.error()->message;
            return ReadStatus::bad_frame;
        }
        if (fd_ < 0) return ReadStatus::closed;
        const auto now = Clock::now();
        if (now >= deadline) return ReadStatus::timeout;
        const auto ms = std::chrono::duration_cast<milliseconds>(deadline - now).count();
        pollfd p{fd_, POLLIN, 0};
        // Bytes OpenSSL already decrypted are invisible to poll.
        const int r = ssl_ && SSL_pending(ssl_.get()) > 0 ? 1 : ::poll(&p, 1, int(std::min<long long>(ms + 1, 1 << 30)));
        if (r < 0) {
            if (errno == EINTR) continue;
            error_ = std::string("poll: ") + std::strerror(errno);
            return ReadStatus::closed;
        }
        if (r == 0) continue;  // re-checks the deadline
        char buf[65536];
        ssize_t n = 0;
        if (ssl_) {
            n = SSL_read(ssl_.get(), buf, sizeof buf);
            if (n <= 0) {
                const int e = SSL_get_error(ssl_.get(), int(n));
                if (e == SSL_ERROR_WANT_READ || e == SSL_ERROR_WANT_WRITE) continue;
                n = (e == SSL_ERROR_ZERO_RETURN || (e == SSL_ERROR_SYSCALL && ERR_peek_error() == 0)) ? 0 : -1;
                if (n < 0) errno = EPROTO;
            }
        } else {
            n = ::recv(fd_, buf, sizeof buf, 0);
        }
        if (n < 0) {
            if (errno == EINTR || errno == EAGAIN) continue;
            error_ = std::string("recv: ") + std::strerror(errno);
            return ReadStatus::closed;
        }
        if (n == 0) {
            decoder_.finish();
            if (auto f = decoder_.next()) {
                out = std::move(*f);
                close();
                return ReadStatus::frame;
            }
            error_ = decoder_.failed() ? std::string(proto::to_string(decoder_.error()->code)) : "closed by peer";
            close();
            return ReadStatus::closed;
        }
        pending_.append(buf, size_t(n));
    }
}

void FrameSocket::start_tls(const std::string& host) {
    std::unique_ptr<SSL_CTX, decltype(&SSL_CTX_free)> ctx(SSL_CTX_new(TLS_client_method()), &SSL_CTX_free);
    if (!ctx) throw std::runtime_error("cannot create a TLS context");
    SSL_CTX_set_min_proto_version(ctx.get(), TLS1_2_VERSION);
    SSL_CTX_set_verify(ctx.get(), SSL_VERIFY_PEER, nullptr);
    const char* ca = std::getenv("OMEGA_TLS_CA");
    if (ca && *ca) {
        if (SSL_CTX_load_verify_locations(ctx.get(), ca, nullptr) != 1)
            throw std::runtime_error(fmt::format("cannot read the CA file '{}' ($OMEGA_TLS_CA)", ca));
    } else {
        SSL_CTX_set_default_verify_paths(ctx.get());
    }
    std::shared_ptr<SSL> ssl(SSL_new(ctx.get()), &SSL_free);
    if (!ssl || SSL_set_fd(ssl.get(), fd_) != 1) throw std::runtime_error("cannot start a TLS session");
    X509_VERIFY_PARAM* param = SSL_get0_param(ssl.get());
    in6_addr a6{};
    in_addr a4{};
    const bool ip = inet_pton(AF_INET, host.c_str(), &a4) == 1 || inet_pton(AF_INET6, host.c_str(), &a6) == 1;
    if (ip) {
        X509_VERIFY_PARAM_set1_ip_asc(param, host.c_str());
    } else {
        SSL_set_tlsext_host_name(ssl.get(), host.c_str());
        SSL_set1_host(ssl.get(), host.c_str());
    }
    if (SSL_connect(ssl.get()) != 1) {
        const long v = SSL_get_verify_result(ssl.get());
        char buf[256] = "handshake failed";
        if (unsigned long e = ERR_get_error()) ERR_error_string_n(e, buf, sizeof buf);
        throw std::runtime_error(v != X509_V_OK ? fmt::format("certificate not trusted: {}", X509_verify_cert_error_string(v))
                                                : std::string(buf));
    }
    ssl_ = std::move(ssl);
}

// ---------------------------------------------------------------- connecting

namespace {

struct Fd {
    int fd = -1;
    ~Fd() {
        if (fd >= 0) ::close(fd);
    }
    int release() {
        int f = fd;
        fd = -1;
        return f;
    }
};

// Non-blocking connect with a deadline; returns 0 or an errno value. The socket is left blocking.
int connect_with_timeout(int fd, const sockaddr* sa, socklen_t len, milliseconds timeout) {
    const int flags = ::fcntl(fd, F_GETFL, 0);
    ::fcntl(fd, F_SETFL, flags | O_NONBLOCK);
    int err = 0;
    if (::connect(fd, sa, len) != 0) {
        err = errno;
        if (err == EINPROGRESS || err == EAGAIN) {
            pollfd p{fd, POLLOUT, 0};
            const int r = ::poll(&p, 1, int(timeout.count()));
            if (r == 0) {
                err = ETIMEDOUT;
            } else if (r < 0) {
                err = errno;
            } else {
                socklen_t l = sizeof err;
                ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &l);
            }
        }
    }
    ::fcntl(fd, F_SETFL, flags);
    return err;
}

int connect_unix(const Address& a, milliseconds timeout, std::string& why) {
    Fd s{::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0)};
    if (s.fd < 0) {
        why = std::strerror(errno);
        return -1;
    }
    sockaddr_un sa{};
    sa.sun_family = AF_UNIX;
    std::memcpy(sa.sun_path, a.path.data(), a.path.size());
    const int err = connect_with_timeout(s.fd, reinterpret_cast<const sockaddr*>(&sa), sizeof sa, timeout);
    if (err != 0) {
        why = std::strerror(err);
        return -1;
    }
    return s.release();
}

int connect_tcp(const Address& a, milliseconds timeout, std::string& why) {
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* res = nullptr;
    const std::string port = std::to_string(a.port);
    if (int rc = ::getaddrinfo(a.host.c_str(), port.c_str(), &hints, &res); rc != 0) {
        why = ::gai_strerror(rc);
        return -1;
    }
    why = "no address";
    int out = -1;
    for (addrinfo* ai = res; ai && out < 0; ai = ai->ai_next) {
        Fd s{::socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC, ai->ai_protocol)};
        if (s.fd < 0) {
            why = std::strerror(errno);
            continue;
        }
        const int err = connect_with_timeout(s.fd, ai->ai_addr, ai->ai_addrlen, timeout);
        if (err != 0) {
            why = std::strerror(err);
            continue;
        }
        int one = 1;
        ::setsockopt(s.fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        out = s.release();
    }
    ::freeaddrinfo(res);
    return out;
}

std::string env_or(const char* name) {
    const char* v = std::getenv(name);
    return v ? v : "";
}

}  // namespace

std::string auth_mac(const std::string& token, const std::string& nonce_hex, const std::string& user) {
    const std::string msg = proto::auth_signed_text(nonce_hex, user);
    unsigned char md[EVP_MAX_MD_SIZE];
    unsigned int len = 0;
    if (!HMAC(EVP_sha256(), token.data(), int(token.size()), reinterpret_cast<const unsigned char*>(msg.data()),
              msg.size(), md, &len))
        throw ClientError(kExitInternal, "HMAC-SHA256 failed");
    std::string hex;
    for (unsigned i = 0; i < len; ++i) hex += fmt::format("{:02x}", md[i]);
    return hex;
}

ClientError error_to_exception(const proto::Error& e, const std::string& address) {
    using proto::ErrorCode;
    const std::string code(proto::to_string(e.code));
    std::string msg = e.message.empty() ? code : fmt::format("{} ({})", e.message, code);
    switch (e.code) {
        case ErrorCode::scene_invalid:
        case ErrorCode::unknown_job:
        case ErrorCode::invalid_state:
            return ClientError(kExitBadInput, msg);
        case ErrorCode::bad_request:
        case ErrorCode::asset_mismatch:
        case ErrorCode::bad_frame:
        case ErrorCode::unknown:
            return ClientError(kExitInternal, fmt::format("{} refused the request: {}", address, msg));
        case ErrorCode::internal:
            return ClientError(kExitInternal, fmt::format("{}: daemon error: {}", address, msg), true);
        case ErrorCode::busy:
        case ErrorCode::shutting_down:
            return ClientError(kExitUnreachable, fmt::format("{} refused the request: {}", address, msg), true);
        default:
            return ClientError(kExitUnreachable, fmt::format("{} refused the request: {}", address, msg));
    }
}

Connection::Connection(Address a, ConnectOptions o, int fd)
    : addr_(std::move(a)), opts_(std::move(o)), sock_(std::make_unique<FrameSocket>(fd)) {}

Connection::~Connection() {
    if (sock_) sock_->close();
}

Connection Connection::open(const Address& addr, const ConnectOptions& opts) {
    std::string why;
    const int fd = addr.kind == Address::Kind::unix_socket ? connect_unix(addr, opts.connect_timeout, why)
                                                           : connect_tcp(addr, opts.connect_timeout, why);
    if (fd < 0)
        throw ClientError(kExitUnreachable, fmt::format("cannot reach the daemon at {}: {}", addr.text(), why), true);
    Connection c(addr, opts, fd);
    if (addr.tls) {
        try {
            c.sock_->start_tls(addr.host);
        } catch (const std::exception& e) {
            throw ClientError(kExitUnreachable, fmt::format("TLS with the daemon at {}: {}", addr.text(), e.what()), true);
        }
    }
    c.handshake();
    return c;
}

void Connection::lost(const std::string& what) const {
    throw ClientError(kExitUnreachable, fmt::format("connection to {} {}", addr_.text(), what), true);
}

void Connection::send(const proto::Frame& f) {
    try {
        sock_->send(f);
    } catch (const std::runtime_error& e) {
        lost(std::string("lost: ") + e.what());
    }
}

std::optional<proto::DecodedFrame> Connection::try_read(Clock::time_point deadline) {
    proto::DecodedFrame f;
    for (;;) {
        switch (sock_->read(deadline, f)) {
            case FrameSocket::ReadStatus::frame:
                if (f.type == proto::MessageType::ping) {  // answered here, never seen by callers
                    send(proto::encode(proto::Pong{f.id}));
                    continue;
                }
                if (f.type == proto::MessageType::bye) lost("closed by the daemon (bye)");
                return f;
            case FrameSocket::ReadStatus::timeout: return std::nullopt;
            case FrameSocket::ReadStatus::closed: lost("closed: " + sock_->error());
            case FrameSocket::ReadStatus::bad_frame: lost("broken: bad frame from the daemon: " + sock_->error());
        }
    }
}

proto::DecodedFrame Connection::read(Clock::time_point deadline) {
    auto f = try_read(deadline);
    if (!f) lost("timed out waiting for the daemon");
    return std::move(*f);
}

proto::DecodedFrame Connection::request(const proto::Frame& f, uint64_t id) {
    send(f);
    const auto deadline = Clock::now() + opts_.reply_timeout;
    for (;;) {
        proto::DecodedFrame r = read(deadline);
        if (r.id == id) return r;
        if (r.type == proto::MessageType::error && r.id == 0) {
            expect<proto::Ok>(r);  // throws the error
        }
    }
}

void Connection::handshake() {
    proto::Hello h;
    h.id = next_id();
    h.client = opts_.client_name;
    const auto hello_id = h.id;
    proto::DecodedFrame r;
    try {
        r = request(proto::encode(h), hello_id);
    } catch (const ClientError& e) {
        if (e.exit_code() == kExitUnreachable) throw;
        throw ClientError(kExitUnreachable, fmt::format("the daemon at {} refused the session: {}", addr_.text(), e.what()));
    }
    welcome_ = expect<proto::Welcome>(r);
    if (welcome_.version < proto::kMinProtocolVersion || welcome_.version > proto::kProtocolVersion)
        throw ClientError(kExitUnreachable, fmt::format("the daemon at {} chose protocol version {}, this omega speaks {}..{}",
                                                        addr_.text(), welcome_.version, proto::kMinProtocolVersion,
                                                        proto::kProtocolVersion));
    if (welcome_.auth != proto::AuthMethod::hmac_sha256) return;

    std::string user = opts_.user.value_or(env_or("OMEGA_USER"));
    if (user.empty()) {
        if (const passwd* pw = ::getpwuid(::getuid())) user = pw->pw_name;
    }
    std::string token = opts_.token.value_or(env_or("OMEGA_TOKEN"));
    if (token.empty()) {
        if (const std::string file = env_or("OMEGA_TOKEN_FILE"); !file.empty()) {
            std::ifstream in(file);
            if (!in) throw ClientError(kExitBadInput, fmt::format("cannot read the token file '{}'", file));
            std::getline(in, token);
        }
    }
    if (token.empty())
        throw ClientError(kExitUnreachable, fmt::format("the daemon at {} asks for authentication: set OMEGA_TOKEN "
                                                        "or OMEGA_TOKEN_FILE (and OMEGA_USER)", addr_.text()));
    proto::Auth a;
    a.id = next_id();
    a.user = user;
    a.mac = auth_mac(token, welcome_.nonce.value_or(""), user);
    auto reply = request(proto::encode(a), a.id);
    expect<proto::Ok>(reply);
}

void Connection::close() {
    if (!sock_ || sock_->fd() < 0) return;
    try {
        sock_->send(proto::encode(proto::Bye{0}));
    } catch (...) {
    }
    sock_->close();
}

}  // namespace omega::client
