#pragma once
// Three error vocabularies: framing (decoder), message fields (decode), and the codes an
// `error` frame carries on the wire. Each has a stable snake_case name used in docs and logs.
#include <string_view>

namespace omega::protocol {

enum class FrameError {
  bad_magic,
  header_too_large,
  payload_too_large,           // over the global payload limit
  payload_too_large_for_type,  // over the limit for this type (0 for types without payload)
  header_not_utf8,
  header_not_yaml,
  header_not_mapping,
  duplicate_key,
  missing_type,
  bad_type,  // `type` is not a scalar string
  unknown_type,
  missing_id,
  bad_id,     // `id` is not a decimal u64
  truncated,  // the stream ended inside a frame
};

enum class DecodeError {
  wrong_message_type,  // decode<T> called on a frame of another type
  missing_field,
  wrong_type,  // the field exists but has the wrong YAML kind or number syntax
  out_of_range,
  invalid_value,  // e.g. a malformed sha256 or an unknown enum name
};

// Codes of the `error` message. `unknown` stands for any code this build does not know, so that
// newer peers can add codes without breaking older ones.
enum class ErrorCode {
  bad_frame,
  bad_request,
  unsupported_version,
  auth_required,
  auth_failed,
  permission_denied,
  unknown_job,
  invalid_state,
  scene_invalid,
  asset_mismatch,
  busy,
  shutting_down,
  internal,
  unknown,
};

std::string_view to_string(FrameError e);
std::string_view to_string(DecodeError e);
std::string_view to_string(ErrorCode e);
ErrorCode error_code_from_string(std::string_view s);  // unknown for unrecognised names

}  // namespace omega::protocol
