#pragma once
// Optional TLS on TCP listeners (OpenSSL), configured by tls_cert and tls_key. One TlsContext is
// made at start-up (main thread) and used by the loop thread to wrap accepted TCP sockets; each
// Connection then owns its SSL session (loop thread only). See docs/security.md.
#include <openssl/ssl.h>

#include <memory>
#include <string>

namespace omega::daemon {

class TlsContext {
 public:
  // Loads the certificate chain (PEM) and private key and checks that they match. TLS 1.2 or
  // newer. Throws std::runtime_error naming the file and OpenSSL's reason.
  TlsContext(const std::string& cert_file, const std::string& key_file);
  ~TlsContext();
  TlsContext(const TlsContext&) = delete;
  TlsContext& operator=(const TlsContext&) = delete;

  // A server-side session on a connected non-blocking socket; the handshake runs inside the
  // first reads and writes. Throws std::runtime_error.
  SSL* wrap(int fd) const;

 private:
  SSL_CTX* ctx_ = nullptr;
};

// The reason for the last OpenSSL error on this thread (and clears the queue).
std::string tls_error_text();

}  // namespace omega::daemon
