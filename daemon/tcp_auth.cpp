#include "daemon/tcp_auth.h"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/rand.h>

#include <stdexcept>

#include "protocol/messages.h"

namespace omega::daemon {

namespace {
std::string hex(const unsigned char* p, std::size_t n) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string s(2 * n, '0');
  for (std::size_t i = 0; i < n; ++i) {
    s[2 * i] = kDigits[p[i] >> 4];
    s[2 * i + 1] = kDigits[p[i] & 15];
  }
  return s;
}
}  // namespace

std::string make_nonce() {
  unsigned char b[protocol::kNonceBytes];
  if (RAND_bytes(b, sizeof b) != 1) throw std::runtime_error("RAND_bytes failed: cannot make an auth nonce");
  return hex(b, sizeof b);
}

std::string expected_mac(const std::string& token, const std::string& nonce_hex, const std::string& user) {
  const std::string msg = protocol::auth_signed_text(nonce_hex, user);
  unsigned char out[EVP_MAX_MD_SIZE];
  unsigned len = 0;
  if (!HMAC(EVP_sha256(), token.data(), static_cast<int>(token.size()),
            reinterpret_cast<const unsigned char*>(msg.data()), msg.size(), out, &len))
    throw std::runtime_error("HMAC-SHA256 failed");
  return hex(out, len);
}

bool check_auth(const std::map<std::string, std::string>& users, const std::string& nonce_hex,
                const std::string& user, const std::string& mac) {
  auto it = users.find(user);
  // An unknown user is checked against a throwaway token so that it takes as long as a known one.
  const std::string token = it != users.end() ? it->second : std::string("omega-unknown-user-token");
  const std::string want = expected_mac(token, nonce_hex, user);
  const bool same = mac.size() == want.size() && CRYPTO_memcmp(mac.data(), want.data(), want.size()) == 0;
  return same && it != users.end();
}

}  // namespace omega::daemon
