#include "daemon/listener.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>

namespace omega::daemon {

namespace {

[[noreturn]] void sys_fail(const std::string& what) { throw std::system_error(errno, std::generic_category(), what); }

bool is_loopback_host(const std::string& h) {
  if (h == "localhost") return true;
  in_addr a4{};
  if (inet_pton(AF_INET, h.c_str(), &a4) == 1) return (ntohl(a4.s_addr) >> 24) == 127;
  in6_addr a6{};
  if (inet_pton(AF_INET6, h.c_str(), &a6) == 1) return IN6_IS_ADDR_LOOPBACK(&a6);
  return false;
}

bool is_loopback_sockaddr(const sockaddr_storage& ss) {
  if (ss.ss_family == AF_INET)
    return (ntohl(reinterpret_cast<const sockaddr_in*>(&ss)->sin_addr.s_addr) >> 24) == 127;
  if (ss.ss_family == AF_INET6) {
    const in6_addr& a = reinterpret_cast<const sockaddr_in6*>(&ss)->sin6_addr;
    if (IN6_IS_ADDR_LOOPBACK(&a)) return true;
    return IN6_IS_ADDR_V4MAPPED(&a) && a.s6_addr[12] == 127;
  }
  return false;
}

// The address alone, without the port: the key of the failed-login rate limit.
std::string sockaddr_host(const sockaddr_storage& ss) {
  char buf[INET6_ADDRSTRLEN] = "?";
  if (ss.ss_family == AF_INET)
    inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(&ss)->sin_addr, buf, sizeof buf);
  else if (ss.ss_family == AF_INET6)
    inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(&ss)->sin6_addr, buf, sizeof buf);
  return buf;
}

std::string sockaddr_text(const sockaddr_storage& ss) {
  char buf[INET6_ADDRSTRLEN] = "?";
  int port = 0;
  if (ss.ss_family == AF_INET) {
    auto* a = reinterpret_cast<const sockaddr_in*>(&ss);
    inet_ntop(AF_INET, &a->sin_addr, buf, sizeof buf);
    port = ntohs(a->sin_port);
    return fmt::format("{}:{}", buf, port);
  }
  if (ss.ss_family == AF_INET6) {
    auto* a = reinterpret_cast<const sockaddr_in6*>(&ss);
    inet_ntop(AF_INET6, &a->sin6_addr, buf, sizeof buf);
    port = ntohs(a->sin6_port);
    return fmt::format("[{}]:{}", buf, port);
  }
  return "?";
}

}  // namespace

std::string ListenAddress::text() const {
  if (kind == Kind::unix_socket) return "unix:" + path;
  return "tcp:" + host + ":" + std::to_string(port);
}

ListenAddress parse_listen_address(const std::string& s) {
  ListenAddress a;
  if (s.rfind("unix:", 0) == 0) {
    a.kind = ListenAddress::Kind::unix_socket;
    a.path = s.substr(5);
    if (a.path.empty()) throw std::invalid_argument("listen address '" + s + "': empty socket path");
    if (a.path.size() >= sizeof(sockaddr_un::sun_path))
      throw std::invalid_argument("listen address '" + s + "': socket path too long");
    return a;
  }
  if (s.rfind("tcp:", 0) == 0) {
    a.kind = ListenAddress::Kind::tcp;
    std::string rest = s.substr(4);
    auto colon = rest.rfind(':');
    if (colon == std::string::npos) throw std::invalid_argument("listen address '" + s + "': expected tcp:HOST:PORT");
    a.host = rest.substr(0, colon);
    if (a.host.size() > 2 && a.host.front() == '[' && a.host.back() == ']') a.host = a.host.substr(1, a.host.size() - 2);
    std::string port = rest.substr(colon + 1);
    if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos ||
        std::stoi(port) > 65535)
      throw std::invalid_argument("listen address '" + s + "': bad port '" + port + "'");
    a.port = std::stoi(port);
    if (a.host.empty()) a.host = "127.0.0.1";
    a.loopback = is_loopback_host(a.host);
    return a;
  }
  throw std::invalid_argument("listen address '" + s + "': expected unix:PATH or tcp:HOST:PORT");
}

Listener::Listener(const ListenAddress& a) {
  text_ = a.text();
  if (a.kind == ListenAddress::Kind::unix_socket) {
    unix_ = true;
    path_ = a.path;
    fd_ = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd_ < 0) sys_fail("socket(" + text_ + ")");
    sockaddr_un sa{};
    sa.sun_family = AF_UNIX;
    std::strncpy(sa.sun_path, a.path.c_str(), sizeof sa.sun_path - 1);
    struct stat st{};
    if (lstat(a.path.c_str(), &st) == 0 && S_ISSOCK(st.st_mode)) {
      // Replace a stale socket only: if someone answers, another daemon is running.
      int probe = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
      bool live = probe >= 0 && connect(probe, reinterpret_cast<sockaddr*>(&sa), sizeof sa) == 0;
      if (probe >= 0) close(probe);
      if (live) {
        close(fd_);
        errno = EADDRINUSE;
        sys_fail("bind(" + text_ + "): another daemon is listening there");
      }
      unlink(a.path.c_str());
    }
    if (bind(fd_, reinterpret_cast<sockaddr*>(&sa), sizeof sa) < 0) {
      int e = errno;
      close(fd_);
      errno = e;
      sys_fail("bind(" + text_ + ")");
    }
    owns_path_ = true;
  } else {
    addrinfo hints{};
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_NUMERICSERV;
    addrinfo* res = nullptr;
    int rc = getaddrinfo(a.host.c_str(), std::to_string(a.port).c_str(), &hints, &res);
    if (rc != 0) throw std::runtime_error("listen address '" + text_ + "': " + gai_strerror(rc));
    fd_ = socket(res->ai_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd_ < 0) {
      freeaddrinfo(res);
      sys_fail("socket(" + text_ + ")");
    }
    int one = 1;
    setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (bind(fd_, res->ai_addr, res->ai_addrlen) < 0) {
      int e = errno;
      freeaddrinfo(res);
      close(fd_);
      errno = e;
      sys_fail("bind(" + text_ + ")");
    }
    freeaddrinfo(res);
    sockaddr_storage ss{};
    socklen_t len = sizeof ss;
    getsockname(fd_, reinterpret_cast<sockaddr*>(&ss), &len);
    text_ = "tcp:" + sockaddr_text(ss);
    loopback_ = is_loopback_sockaddr(ss);
  }
  if (listen(fd_, 128) < 0) {
    int e = errno;
    close(fd_);
    errno = e;
    sys_fail("listen(" + text_ + ")");
  }
}

Listener Listener::adopt(int fd) {
  Listener l;
  l.fd_ = fd;
  sockaddr_storage ss{};
  socklen_t len = sizeof ss;
  getsockname(fd, reinterpret_cast<sockaddr*>(&ss), &len);
  if (ss.ss_family == AF_UNIX) {
    l.unix_ = true;
    auto* su = reinterpret_cast<sockaddr_un*>(&ss);
    l.text_ = fmt::format("unix:{} (systemd)", su->sun_path);
  } else {
    l.text_ = "tcp:" + sockaddr_text(ss) + " (systemd)";
    l.loopback_ = is_loopback_sockaddr(ss);
  }
  return l;
}

Listener::Listener(Listener&& o) noexcept
    : fd_(o.fd_), unix_(o.unix_), loopback_(o.loopback_), owns_path_(o.owns_path_), path_(std::move(o.path_)), text_(std::move(o.text_)) {
  o.fd_ = -1;
  o.owns_path_ = false;
}

Listener::~Listener() {
  if (fd_ >= 0) close(fd_);
  if (owns_path_) unlink(path_.c_str());
}

int Listener::accept_one(Peer& peer) {
  sockaddr_storage ss{};
  socklen_t len = sizeof ss;
  int fd = accept4(fd_, reinterpret_cast<sockaddr*>(&ss), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd < 0) return -1;
  peer = Peer{};
  peer.unix_socket = unix_;
  peer.loopback_listener = loopback_;
  if (unix_) {
    ucred cred{};
    socklen_t clen = sizeof cred;
    if (getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &clen) == 0) {
      peer.uid = cred.uid;
      peer.name = "uid " + std::to_string(cred.uid) + " pid " + std::to_string(cred.pid);
    } else {
      peer.name = "unix peer (no credentials)";
    }
  } else {
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    peer.name = sockaddr_text(ss);
    peer.address = sockaddr_host(ss);
  }
  return fd;
}

}  // namespace omega::daemon
