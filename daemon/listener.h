#pragma once
// Listening sockets: "unix:/path" and "tcp:host:port" (the Server refuses a non-loopback TCP address
// unless TCP authentication is configured), or
// sockets handed over by systemd. All non-blocking; accept() is called from the loop thread.
#include <optional>
#include <string>

namespace omega::daemon {

struct ListenAddress {
  enum class Kind { unix_socket, tcp } kind = Kind::unix_socket;
  std::string path;  // unix
  std::string host;  // tcp
  int port = 0;      // tcp; 0 = any free port (tests)
  bool loopback = false;  // tcp: 127.0.0.0/8, ::1 or localhost
  std::string text() const;
};

// Throws std::invalid_argument with a message naming the address for a malformed address. An
// empty TCP host means 127.0.0.1 (loopback by default).
ListenAddress parse_listen_address(const std::string& s);

struct Peer {
  bool unix_socket = false;
  bool loopback_listener = false;  // accepted on a loopback TCP listener
  std::optional<unsigned> uid;  // SO_PEERCRED on unix sockets
  std::string name;             // for logs: "uid 1000 pid 42" or "127.0.0.1:5555"
  std::string address;          // TCP: the source address without the port ("127.0.0.1", "::1")
};

class Listener {
 public:
  // Binds and listens. Throws std::system_error naming the address. A stale unix socket file
  // (nobody listening) is replaced; a live one is an error.
  explicit Listener(const ListenAddress& a);
  // Adopts a socket from systemd.
  static Listener adopt(int fd);
  Listener(Listener&& o) noexcept;
  Listener& operator=(Listener&&) = delete;
  Listener(const Listener&) = delete;
  ~Listener();

  int fd() const { return fd_; }
  bool unix_socket() const { return unix_; }
  bool loopback() const { return loopback_; }  // TCP bound to a loopback address
  std::string text() const { return text_; }  // "unix:/run/x.sock" or "tcp:127.0.0.1:7171" (actual port)

  // Loop thread: the next connection (non-blocking, close-on-exec), or -1 when none is waiting.
  int accept_one(Peer& peer);

 private:
  Listener() = default;
  int fd_ = -1;
  bool unix_ = false;
  bool loopback_ = false;
  bool owns_path_ = false;
  std::string path_;
  std::string text_;
};

}  // namespace omega::daemon
