#pragma once
// The closed set of frame types. The decoder rejects any other `type` (unknown_type).
#include <cstddef>
#include <optional>
#include <string_view>

namespace omega::protocol {

enum class MessageType {
  hello, welcome, auth, ok, error, ping, pong, bye,
  submit, need_assets, asset, accepted,
  status, job_info, list, job_list,
  cancel, pause, resume, set_priority, delete_job,
  subscribe, unsubscribe, tile, progress, done, fetch, image,
  work_request, work_unit, asset_request, unit_result, unit_stop,
};
inline constexpr std::size_t kMessageTypeCount = static_cast<std::size_t>(MessageType::unit_stop) + 1;

std::string_view to_string(MessageType t);
std::optional<MessageType> message_type_from_string(std::string_view s);

// Only these carry a payload; every other type must have payload length 0.
bool carries_payload(MessageType t);

}  // namespace omega::protocol
