#pragma once
// One client connection: a non-blocking socket, an incremental frame decoder with limits, and a
// bounded, coalescing output queue. Owned by the Server; loop thread only.
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <openssl/ssl.h>

#include "daemon/listener.h"
#include "daemon/output_queue.h"
#include "protocol/frame_decoder.h"
#include "protocol/messages.h"

namespace omega::daemon {

// A submit waiting for its assets or for validation.
struct PendingSubmit {
  protocol::Submit submit;
  std::set<std::string> missing;  // sha256 still to come
  bool validating = false;
};

// An `omega worker` session on a connection (docs/farm.md "Workers"). Loop thread only.
struct WorkerSession {
  std::string name;  // "conn ID (the worker's own name)"
  std::uint32_t threads = 1;
  std::optional<std::uint64_t> waiting;  // a work_request not yet answered
  std::set<std::pair<std::uint64_t, std::uint64_t>> units;  // (job, unit) it renders now
  std::map<std::uint64_t, std::uint64_t> done;  // job -> units finished in this session
  double samples_per_s = 0;  // of its last unit
};

class Connection {
 public:
  // ssl: a TLS session on fd (owned from now on), or nullptr for plain bytes.
  Connection(int fd, std::uint64_t id, Peer peer, const protocol::DecoderLimits& limits, std::size_t out_limit,
             SSL* ssl = nullptr);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  int fd() const { return fd_; }
  std::uint64_t id() const { return id_; }
  const Peer& peer() const { return peer_; }

  enum class ReadStatus { open, eof, error };
  // Reads what the socket holds (up to a budget, so one client cannot starve the others) and
  // appends complete frames to `out`. On a framing error the frames before it are still returned
  // and framing_error() is set.
  ReadStatus read_frames(std::vector<protocol::DecodedFrame>& out);
  const std::optional<protocol::Failure<protocol::FrameError>>& framing_error() const { return decoder_.error(); }
  // Inside a frame: when its bytes last arrived; nullopt between frames. A client that sends
  // half a frame and stalls is cut by Server::sweep_timeouts (frame_timeout_s).
  std::optional<std::chrono::steady_clock::time_point> partial_since() const { return partial_since_; }
  std::chrono::steady_clock::time_point opened_at() const { return opened_at_; }

  void send(const protocol::Frame& f);  // never dropped; counts against the limit
  void send_coalesced(const CoalesceKey& key, const std::string& header,
                      std::shared_ptr<const std::string> payload);
  // Writes what the socket takes now. False on a write error (the peer is gone).
  bool flush();
  bool wants_write() const { return !out_.empty() || tls_want_write_; }
  bool tls() const { return ssl_ != nullptr; }
  const std::string& tls_error() const { return tls_error_; }  // why a TLS session failed
  bool over_limit() const { return out_.owned_bytes() > out_limit_; }
  const OutputQueue& output() const { return out_; }

  // Session state.
  bool welcomed = false;
  bool authenticated = false;  // welcomed and, on TCP with tcp_users, the HMAC answer checked
  std::string nonce;    // the challenge sent in welcome (TCP with auth)
  std::string user;     // job owner: the uid in decimal on unix sockets, the TCP user name after
                        // HMAC auth, "tcp" on loopback TCP without auth
  bool closing = false; // close once the output is written (after bye or a fatal error)
  bool dead = false;    // close now
  std::map<std::uint64_t, PendingSubmit> pending;  // by submit id
  std::set<std::pair<std::uint64_t, std::uint64_t>> subscriptions;  // (job, subscribe id)
  bool write_armed = false;  // EPOLLOUT registered
  // `omega worker` sessions (docs/farm.md "Workers"). worker_role: a tcp_users entry with role
  // worker, which may send only the worker messages (and ping, bye).
  bool worker_role = false;
  std::optional<WorkerSession> worker;  // set by its first work_request

 private:
  int fd_;
  std::uint64_t id_;
  Peer peer_;
  protocol::FrameDecoder decoder_;
  std::string inbuf_;  // bytes read but not yet taken by the decoder
  std::chrono::steady_clock::time_point opened_at_ = std::chrono::steady_clock::now();
  std::optional<std::chrono::steady_clock::time_point> partial_since_;
  OutputQueue out_;
  std::size_t out_limit_;
  SSL* ssl_ = nullptr;
  bool tls_want_write_ = false;  // the TLS handshake waits for the socket to take bytes
  std::string tls_error_;
  // Plain or TLS I/O: > 0 bytes moved, 0 end of stream (read), -1 would block, -2 error.
  long io_read(char* buf, std::size_t n);
  long io_write(const char* buf, std::size_t n);
};

}  // namespace omega::daemon
