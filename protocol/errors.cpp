#include "protocol/errors.h"

#include <array>

namespace omega::protocol {

namespace {
constexpr std::array<std::string_view, 14> kFrameErrors{
    "bad_magic", "header_too_large", "payload_too_large", "payload_too_large_for_type",
    "header_not_utf8", "header_not_yaml", "header_not_mapping", "duplicate_key", "missing_type",
    "bad_type", "unknown_type", "missing_id", "bad_id", "truncated",
};
constexpr std::array<std::string_view, 5> kDecodeErrors{
    "wrong_message_type", "missing_field", "wrong_type", "out_of_range", "invalid_value",
};
constexpr std::array<std::string_view, 14> kErrorCodes{
    "bad_frame", "bad_request", "unsupported_version", "auth_required", "auth_failed",
    "permission_denied", "unknown_job", "invalid_state", "scene_invalid", "asset_mismatch",
    "busy", "shutting_down", "internal", "unknown",
};
}  // namespace

std::string_view to_string(FrameError e) { return kFrameErrors.at(static_cast<std::size_t>(e)); }
std::string_view to_string(DecodeError e) { return kDecodeErrors.at(static_cast<std::size_t>(e)); }
std::string_view to_string(ErrorCode e) { return kErrorCodes.at(static_cast<std::size_t>(e)); }

ErrorCode error_code_from_string(std::string_view s) {
  for (std::size_t i = 0; i < kErrorCodes.size(); ++i)
    if (kErrorCodes[i] == s) return static_cast<ErrorCode>(i);
  return ErrorCode::unknown;
}

}  // namespace omega::protocol
