#include "protocol/message_type.h"

#include <array>

namespace omega::protocol {

namespace {
constexpr std::array<std::string_view, kMessageTypeCount> kNames{
    "hello", "welcome", "auth", "ok", "error", "ping", "pong", "bye",
    "submit", "need_assets", "asset", "accepted",
    "status", "job_info", "list", "job_list",
    "cancel", "pause", "resume", "set_priority", "delete",
    "subscribe", "unsubscribe", "tile", "progress", "done", "fetch", "image",
    "work_request", "work_unit", "asset_request", "unit_result", "unit_stop",
};
}  // namespace

std::string_view to_string(MessageType t) { return kNames[static_cast<std::size_t>(t)]; }

std::optional<MessageType> message_type_from_string(std::string_view s) {
  for (std::size_t i = 0; i < kNames.size(); ++i)
    if (kNames[i] == s) return static_cast<MessageType>(i);
  return std::nullopt;
}

bool carries_payload(MessageType t) {
  return t == MessageType::submit || t == MessageType::asset || t == MessageType::tile ||
         t == MessageType::image || t == MessageType::work_unit || t == MessageType::unit_result;
}

}  // namespace omega::protocol
