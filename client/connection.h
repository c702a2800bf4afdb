#pragma once
// A session with omegad: connect (unix or TCP, with a timeout), hello/welcome version
// negotiation, HMAC authentication on TCP, then frames in both directions. Framing and messages
// come from the protocol library; this file only moves bytes.
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "address.h"
#include "client_error.h"
#include "protocol/frame.h"
#include "protocol/frame_decoder.h"
#include "protocol/messages.h"

struct ssl_st;

namespace omega::client {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// Frames over a connected stream socket. Blocking writes; reads wait with a deadline (poll).
// Used by Connection and by the tests' fake daemon.
class FrameSocket {
public:
    explicit FrameSocket(int fd, protocol::DecoderLimits limits = {});
    ~FrameSocket();
    FrameSocket(const FrameSocket&) = delete;
    FrameSocket& operator=(const FrameSocket&) = delete;
    FrameSocket(FrameSocket&& o) noexcept;
    FrameSocket& operator=(FrameSocket&& o) noexcept;

    int fd() const { return fd_; }
    // False once the peer closed or an I/O error happened. Throws std::runtime_error on error.
    void send(const protocol::Frame& f);
    enum class ReadStatus { frame, timeout, closed, bad_frame };
    // Waits until a frame is complete or the deadline passes. On bad_frame, error() says why.
    ReadStatus read(Clock::time_point deadline, protocol::DecodedFrame& out);
    const std::string& error() const { return error_; }
    void close();
    // Wraps the (blocking, connected) socket in TLS and verifies the daemon's certificate for
    // `host` against $OMEGA_TLS_CA (a PEM file) or the system's CAs. Throws std::runtime_error.
    void start_tls(const std::string& host);

private:
    int fd_ = -1;
    std::shared_ptr<ssl_st> ssl_;  // TLS session, or null for plain bytes
    protocol::FrameDecoder decoder_;
    std::string pending_;  // bytes read but not yet taken by the decoder
    std::string error_;
};

struct ConnectOptions {
    milliseconds connect_timeout{5000};
    milliseconds reply_timeout{30000};  // one request's reply
    std::string client_name = "omega/0.1";
    // TCP authentication; defaults come from $OMEGA_USER (else the login name) and
    // $OMEGA_TOKEN (else the first line of $OMEGA_TOKEN_FILE).
    std::optional<std::string> user;
    std::optional<std::string> token;
};

class Connection {
public:
    // Connects and completes the handshake. Throws ClientError: exit 3 (naming the address) when
    // the daemon cannot be reached, refuses the version or the credentials; exit 2 for a bad
    // address.
    static Connection open(const Address& addr, const ConnectOptions& opts = {});

    Connection(Connection&&) noexcept = default;
    Connection& operator=(Connection&&) noexcept = default;
    ~Connection();

    const Address& address() const { return addr_; }
    const protocol::Welcome& welcome() const { return welcome_; }
    const ConnectOptions& options() const { return opts_; }
    uint64_t next_id() { return next_id_++; }

    void send(const protocol::Frame& f);
    // The next frame, any id. Throws ClientError (exit 3, transient) on timeout, a closed
    // connection or a bad frame.
    protocol::DecodedFrame read(Clock::time_point deadline);
    // Like read, but nullopt when the deadline passes.
    std::optional<protocol::DecodedFrame> try_read(Clock::time_point deadline);
    // Sends a request and returns the first frame that echoes its id (others are dropped).
    // An `error` reply is thrown as ClientError (see error_to_exception).
    protocol::DecodedFrame request(const protocol::Frame& f, uint64_t id);
    // Decodes a reply of the expected type; an `error` frame becomes ClientError, and any other
    // type or a malformed one an internal error.
    template <class T>
    T expect(const protocol::DecodedFrame& f) const;
    // Sends bye (best effort) and closes.
    void close();

private:
    Connection(Address a, ConnectOptions o, int fd);
    void handshake();
    [[noreturn]] void lost(const std::string& what) const;

    Address addr_;
    ConnectOptions opts_;
    std::unique_ptr<FrameSocket> sock_;
    protocol::Welcome welcome_;
    uint64_t next_id_ = 1;
};

// The exit code for an `error` reply: scene_invalid, unknown_job, invalid_state → 2 (bad
// input); bad_request, asset_mismatch, internal, unknown codes → 1; the rest (permission_denied,
// busy, shutting_down, auth_*, unsupported_version) → 3 (refused). busy, shutting_down and
// internal are transient.
ClientError error_to_exception(const protocol::Error& e, const std::string& address);

// hex(HMAC-SHA256(token, "omega-auth-v1\n" + nonce + "\n" + user)).
std::string auth_mac(const std::string& token, const std::string& nonce_hex, const std::string& user);

template <class T>
T Connection::expect(const protocol::DecodedFrame& f) const {
    if (f.type == protocol::MessageType::error) {
        auto e = protocol::decode<protocol::Error>(f);
        if (!e) throw ClientError(kExitInternal, "malformed error reply from " + addr_.text() + ": " + e.message());
        throw error_to_exception(*e, addr_.text());
    }
    auto m = protocol::decode<T>(f);
    if (!m)
        throw ClientError(kExitInternal, "unexpected reply from " + addr_.text() + " (" +
                                             std::string(protocol::to_string(f.type)) + "): " + m.message());
    return std::move(m).value();
}

}  // namespace omega::client
