#pragma once
// The TCP challenge-response (docs/protocol.md, Authentication; threat model in docs/security.md):
// the daemon sends a fresh random nonce, the client answers
// HMAC-SHA256(token, "omega-auth-v1\n" + nonce_hex + "\n" + user). The token never crosses the
// wire. Pure functions; any thread.
#include <map>
#include <string>

namespace omega::daemon {

// 32 bytes from OpenSSL's CSPRNG as 64 lowercase hex digits. Throws std::runtime_error if the
// generator fails (never falls back to a weak source).
std::string make_nonce();

// hex(HMAC-SHA256(token, auth_signed_text(nonce_hex, user))).
std::string expected_mac(const std::string& token, const std::string& nonce_hex, const std::string& user);

// True when `mac` is the right answer for `user` under `users` (user -> token). The comparison is
// constant-time, and an unknown user costs the same as a wrong MAC.
bool check_auth(const std::map<std::string, std::string>& users, const std::string& nonce_hex,
                const std::string& user, const std::string& mac);

}  // namespace omega::daemon
