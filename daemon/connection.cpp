#include "daemon/connection.h"

#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cerrno>

namespace omega::daemon {

Connection::Connection(int fd, std::uint64_t id, Peer peer, const protocol::DecoderLimits& limits,
                       std::size_t out_limit)
    : fd_(fd), id_(id), peer_(std::move(peer)), decoder_(limits), out_limit_(out_limit) {}

Connection::~Connection() {
  if (fd_ >= 0) close(fd_);
}

Connection::ReadStatus Connection::read_frames(std::vector<protocol::DecodedFrame>& out) {
  constexpr std::size_t kBudget = 4 << 20;  // per wake-up; level-triggered epoll brings us back
  std::size_t total = 0;
  char buf[65536];
  ReadStatus status = ReadStatus::open;
  while (total < kBudget && !decoder_.failed()) {
    // Feed what is buffered first; the decoder pauses when it holds max_ready_frames.
    while (!inbuf_.empty() && !decoder_.failed()) {
      std::size_t took = decoder_.feed(std::string_view(inbuf_));
      inbuf_.erase(0, took);
      while (auto f = decoder_.next()) out.push_back(std::move(*f));
      if (took == 0 && decoder_.ready_frames() == 0) break;
    }
    if (decoder_.failed() || !inbuf_.empty()) break;
    ssize_t n = recv(fd_, buf, sizeof buf, 0);
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
    if (errno == EINTR) continue;
    if (errno != EAGAIN && errno != EWOULDBLOCK) {
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
