#include "daemon/connection.h"

#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <openssl/err.h>

#include <algorithm>
#include <cerrno>

#include "daemon/tls.h"

namespace omega::daemon {

Connection::Connection(int fd, std::uint64_t id, Peer peer, const protocol::DecoderLimits& limits,
                       std::size_t out_limit, SSL* ssl)
    : fd_(fd), id_(id), peer_(std::move(peer)), decoder_(limits), out_limit_(out_limit), ssl_(ssl) {}

Connection::~Connection() {
  if (ssl_) SSL_free(ssl_);
  if (fd_ >= 0) close(fd_);
}

long Connection::io_read(char* buf, std::size_t n) {
  if (!ssl_) {
    for (;;) {
      ssize_t r = ::recv(fd_, buf, n, 0);
      if (r >= 0) return r;
      if (errno == EINTR) continue;
      return errno == EAGAIN || errno == EWOULDBLOCK ? -1 : -2;
    }
  }
  int r = SSL_read(ssl_, buf, static_cast<int>(n));
  if (r > 0) {
    tls_want_write_ = false;
    return r;
  }
  switch (SSL_get_error(ssl_, r)) {
    case SSL_ERROR_WANT_READ: tls_want_write_ = false; return -1;
    case SSL_ERROR_WANT_WRITE: tls_want_write_ = true; return -1;
    case SSL_ERROR_ZERO_RETURN: return 0;
    case SSL_ERROR_SYSCALL:
      if (ERR_peek_error() == 0) return errno == 0 ? 0 : -2;  // the peer closed without close_notify
      [[fallthrough]];
    default:
      tls_error_ = tls_error_text();
      return -2;
  }
}

long Connection::io_write(const char* buf, std::size_t n) {
  if (!ssl_) {
    for (;;) {
      ssize_t w = ::send(fd_, buf, n, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (w >= 0) return w;
      if (errno == EINTR) continue;
      return errno == EAGAIN || errno == EWOULDBLOCK ? -1 : -2;
    }
  }
  int w = SSL_write(ssl_, buf, static_cast<int>(std::min<std::size_t>(n, 1 << 30)));
  if (w > 0) return w;
  switch (SSL_get_error(ssl_, w)) {
    case SSL_ERROR_WANT_READ:
    case SSL_ERROR_WANT_WRITE: return -1;
    default:
      tls_error_ = tls_error_text();
      return -2;
  }
}

Connection::ReadStatus Connection::read_frames(std::vector<protocol::DecodedFrame>& out) {
  constexpr std::size_t kBudget = 4 << 20;  // per wake-up; level-triggered epoll brings us back
  std::size_t total = 0;
  char buf[65536];
  ReadStatus status = ReadStatus::open;
  // With TLS, also drain what OpenSSL already decrypted: epoll cannot see those bytes.
  while ((total < kBudget || (ssl_ && SSL_pending(ssl_) > 0)) && !decoder_.failed()) {
    // Feed what is buffered first; the decoder pauses when it holds max_ready_frames.
    while (!inbuf_.empty() && !decoder_.failed()) {
      std::size_t took = decoder_.feed(std::string_view(inbuf_));
      inbuf_.erase(0, took);
      while (auto f = decoder_.next()) out.push_back(std::move(*f));
      if (took == 0 && decoder_.ready_frames() == 0) break;
    }
    if (decoder_.failed() || !inbuf_.empty()) break;
    long n = io_read(buf, sizeof buf);
    if (n > 0) {
      total += std::size_t(n);
      inbuf_.append(buf, std::size_t(n));
      continue;
    }
    if (n == 0) {
      decoder_.finish();
      status = ReadStatus::eof;
      break;
    }
    if (n == -2) {
      decoder_.finish();  // a reset inside a frame is a truncated frame
      status = ReadStatus::error;
    }
    break;
  }
  while (auto f = decoder_.next()) out.push_back(std::move(*f));
  if (decoder_.at_frame_boundary() && inbuf_.empty()) {
    partial_since_.reset();
  } else if (total > 0 || !partial_since_) {
    partial_since_ = std::chrono::steady_clock::now();  // inside a frame, and bytes came
  }
  return status;
}

void Connection::send(const protocol::Frame& f) { out_.push(protocol::encode_frame(f)); }

void Connection::send_coalesced(const CoalesceKey& key, const std::string& header,
                                std::shared_ptr<const std::string> payload) {
  std::string head;
  auto prelude = protocol::encode_prelude(static_cast<std::uint32_t>(header.size()), payload ? payload->size() : 0);
  head.append(reinterpret_cast<const char*>(prelude.data()), prelude.size());
  head += header;
  out_.push_coalesced(key, std::move(head), std::move(payload));
}

bool Connection::flush() {
  if (ssl_) {
    if (!SSL_is_init_finished(ssl_)) {  // drive the handshake (also when EPOLLOUT woke us)
      int r = SSL_do_handshake(ssl_);
      if (r != 1) {
        int e = SSL_get_error(ssl_, r);
        if (e == SSL_ERROR_WANT_READ || e == SSL_ERROR_WANT_WRITE) {
          tls_want_write_ = e == SSL_ERROR_WANT_WRITE;
          return true;
        }
        tls_error_ = tls_error_text();
        return false;
      }
      tls_want_write_ = false;
    }
    while (!out_.empty()) {
      iovec iov[2];  // fill_iov wants room for a frame's head and payload; one write each
      if (out_.fill_iov(iov, 2) == 0) break;
      long w = io_write(static_cast<const char*>(iov[0].iov_base), iov[0].iov_len);
      if (w > 0) {
        out_.consume(std::size_t(w));
        continue;
      }
      return w == -1;
    }
    return true;
  }
  while (!out_.empty()) {
    iovec iov[64];
    int n = out_.fill_iov(iov, 64);
    if (n == 0) break;
    msghdr msg{};
    msg.msg_iov = iov;
    msg.msg_iovlen = static_cast<std::size_t>(n);
    ssize_t w = sendmsg(fd_, &msg, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (w > 0) {
      out_.consume(std::size_t(w));
      continue;
    }
    if (w < 0 && errno == EINTR) continue;
    if (w < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    return false;
  }
  return true;
}

}  // namespace omega::daemon
