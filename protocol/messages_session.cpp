// hello, welcome, auth, ok, error, ping, pong, bye.
#include "protocol/messages_common.h"

namespace omega::protocol {

using detail::begin_header;
using detail::check_frame;
using detail::finish;
using detail::finish_decode;

Frame encode(const Hello& m) {
  auto w = begin_header(MessageType::hello, m.id);
  w.field_u("version", m.version).field_u("min_version", m.min_version).field("client", m.client);
  return finish(w);
}

template <>
Result<Hello, DecodeError> decode<Hello>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::hello)) return *e;
  FieldReader r(f.header);
  Hello m;
  m.id = f.id;
  m.version = static_cast<std::uint32_t>(r.u64("version", 1, UINT32_MAX));
  m.min_version = static_cast<std::uint32_t>(r.u64("min_version", 1, UINT32_MAX));
  m.client = r.str("client", kMaxNameBytes);
  if (r.ok() && m.min_version > m.version)
    r.fail(DecodeError::out_of_range, "min_version", "greater than version");
  return finish_decode(r, std::move(m));
}

Frame encode(const Welcome& m) {
  auto w = begin_header(MessageType::welcome, m.id);
  w.field_u("version", m.version).field("server", m.server).field("auth", to_string(m.auth));
  if (m.nonce) w.field("nonce", *m.nonce);
  if (m.user) w.field("user", *m.user);
  return finish(w);
}

template <>
Result<Welcome, DecodeError> decode<Welcome>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::welcome)) return *e;
  FieldReader r(f.header);
  Welcome m;
  m.id = f.id;
  m.version = static_cast<std::uint32_t>(r.u64("version", 1, UINT32_MAX));
  m.server = r.str("server", kMaxNameBytes);
  std::string auth = r.str("auth", 64);
  if (auth == "none") m.auth = AuthMethod::none;
  else if (auth == "peer") m.auth = AuthMethod::peer;
  else if (auth == "hmac-sha256") m.auth = AuthMethod::hmac_sha256;
  else if (r.ok()) r.fail(DecodeError::invalid_value, "auth", "'" + auth + "' is not one of none|peer|hmac-sha256");
  m.nonce = r.opt_str("nonce", 2 * kNonceBytes);
  m.user = r.opt_str("user", kMaxNameBytes);
  if (r.ok()) {
    bool want_nonce = m.auth == AuthMethod::hmac_sha256;
    if (want_nonce && !m.nonce) r.fail(DecodeError::missing_field, "nonce", "required for hmac-sha256");
    else if (!want_nonce && m.nonce) r.fail(DecodeError::invalid_value, "nonce", "only sent with hmac-sha256");
    else if (m.nonce && (m.nonce->size() != 2 * kNonceBytes || !is_lower_hex(*m.nonce)))
      r.fail(DecodeError::invalid_value, "nonce", "expected 64 lowercase hex digits");
  }
  return finish_decode(r, std::move(m));
}

Frame encode(const Auth& m) {
  auto w = begin_header(MessageType::auth, m.id);
  w.field("user", m.user).field("mac", m.mac);
  return finish(w);
}

template <>
Result<Auth, DecodeError> decode<Auth>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::auth)) return *e;
  FieldReader r(f.header);
  Auth m;
  m.id = f.id;
  m.user = r.str("user", kMaxNameBytes);
  if (r.ok() && m.user.empty()) r.fail(DecodeError::invalid_value, "user", "must not be empty");
  m.mac = detail::read_sha256(r, "mac");
  return finish_decode(r, std::move(m));
}

Frame encode(const Error& m) {
  auto w = begin_header(MessageType::error, m.id);
  w.field("code", to_string(m.code)).field("message", m.message);
  return finish(w);
}

template <>
Result<Error, DecodeError> decode<Error>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::error)) return *e;
  FieldReader r(f.header);
  Error m;
  m.id = f.id;
  m.code = error_code_from_string(r.str("code", 64));
  m.message = r.str("message", kMaxMessageBytes);
  return finish_decode(r, std::move(m));
}

namespace {
// ok, ping, pong, bye, list: nothing but type and id.
template <class T>
Frame encode_bare(const T& m, MessageType t) {
  auto w = begin_header(t, m.id);
  return finish(w);
}
template <class T>
Result<T, DecodeError> decode_bare(const DecodedFrame& f, MessageType t) {
  if (auto e = check_frame(f, t)) return *e;
  T m;
  m.id = f.id;
  return m;
}
}  // namespace

Frame encode(const Ok& m) { return encode_bare(m, MessageType::ok); }
Frame encode(const Ping& m) { return encode_bare(m, MessageType::ping); }
Frame encode(const Pong& m) { return encode_bare(m, MessageType::pong); }
Frame encode(const Bye& m) { return encode_bare(m, MessageType::bye); }
Frame encode(const List& m) { return encode_bare(m, MessageType::list); }
template <>
Result<Ok, DecodeError> decode<Ok>(const DecodedFrame& f) { return decode_bare<Ok>(f, MessageType::ok); }
template <>
Result<Ping, DecodeError> decode<Ping>(const DecodedFrame& f) { return decode_bare<Ping>(f, MessageType::ping); }
template <>
Result<Pong, DecodeError> decode<Pong>(const DecodedFrame& f) { return decode_bare<Pong>(f, MessageType::pong); }
template <>
Result<Bye, DecodeError> decode<Bye>(const DecodedFrame& f) { return decode_bare<Bye>(f, MessageType::bye); }
template <>
Result<List, DecodeError> decode<List>(const DecodedFrame& f) { return decode_bare<List>(f, MessageType::list); }

}  // namespace omega::protocol
