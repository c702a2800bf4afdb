// The Message variant: dispatch between frame types and typed messages.
#include "protocol/messages.h"

namespace omega::protocol {

namespace {

template <class T>
constexpr MessageType type_for();
template <> constexpr MessageType type_for<Hello>() { return MessageType::hello; }
template <> constexpr MessageType type_for<Welcome>() { return MessageType::welcome; }
template <> constexpr MessageType type_for<Auth>() { return MessageType::auth; }
template <> constexpr MessageType type_for<Ok>() { return MessageType::ok; }
template <> constexpr MessageType type_for<Error>() { return MessageType::error; }
template <> constexpr MessageType type_for<Ping>() { return MessageType::ping; }
template <> constexpr MessageType type_for<Pong>() { return MessageType::pong; }
template <> constexpr MessageType type_for<Bye>() { return MessageType::bye; }
template <> constexpr MessageType type_for<Submit>() { return MessageType::submit; }
template <> constexpr MessageType type_for<NeedAssets>() { return MessageType::need_assets; }
template <> constexpr MessageType type_for<Asset>() { return MessageType::asset; }
template <> constexpr MessageType type_for<Accepted>() { return MessageType::accepted; }
template <> constexpr MessageType type_for<Status>() { return MessageType::status; }
template <> constexpr MessageType type_for<JobInfoReply>() { return MessageType::job_info; }
template <> constexpr MessageType type_for<List>() { return MessageType::list; }
template <> constexpr MessageType type_for<JobList>() { return MessageType::job_list; }
template <> constexpr MessageType type_for<SetPriority>() { return MessageType::set_priority; }
template <> constexpr MessageType type_for<Tile>() { return MessageType::tile; }
template <> constexpr MessageType type_for<Progress>() { return MessageType::progress; }
template <> constexpr MessageType type_for<Done>() { return MessageType::done; }
template <> constexpr MessageType type_for<Image>() { return MessageType::image; }
template <> constexpr MessageType type_for<Cancel>() { return Cancel::kType; }
template <> constexpr MessageType type_for<Pause>() { return Pause::kType; }
template <> constexpr MessageType type_for<Resume>() { return Resume::kType; }
template <> constexpr MessageType type_for<Delete>() { return Delete::kType; }
template <> constexpr MessageType type_for<Subscribe>() { return Subscribe::kType; }
template <> constexpr MessageType type_for<Unsubscribe>() { return Unsubscribe::kType; }
template <> constexpr MessageType type_for<Fetch>() { return Fetch::kType; }
template <> constexpr MessageType type_for<WorkRequest>() { return MessageType::work_request; }
template <> constexpr MessageType type_for<WorkUnit>() { return MessageType::work_unit; }
template <> constexpr MessageType type_for<AssetRequest>() { return MessageType::asset_request; }
template <> constexpr MessageType type_for<UnitResult>() { return MessageType::unit_result; }
template <> constexpr MessageType type_for<UnitStop>() { return MessageType::unit_stop; }

// The variant's alternatives appear in MessageType order, which lets decode_message find the
// alternative by index. Checked here at compile time.
template <std::size_t... I>
constexpr bool variant_matches_types(std::index_sequence<I...>) {
  return ((type_for<std::variant_alternative_t<I, Message>>() == static_cast<MessageType>(I)) && ...);
}
static_assert(std::variant_size_v<Message> == kMessageTypeCount);
static_assert(variant_matches_types(std::make_index_sequence<kMessageTypeCount>{}));

template <std::size_t I>
Result<Message, DecodeError> decode_as(const DecodedFrame& f) {
  using T = std::variant_alternative_t<I, Message>;
  auto r = decode<T>(f);
  if (!r) return r.error();
  return Message(std::in_place_index<I>, std::move(r).value());
}

template <std::size_t... I>
Result<Message, DecodeError> dispatch(const DecodedFrame& f, std::index_sequence<I...>) {
  using Fn = Result<Message, DecodeError> (*)(const DecodedFrame&);
  static constexpr Fn table[] = {&decode_as<I>...};
  return table[static_cast<std::size_t>(f.type)](f);
}

}  // namespace

MessageType type_of(const Message& m) { return static_cast<MessageType>(m.index()); }

std::uint64_t id_of(const Message& m) {
  return std::visit([](const auto& x) { return x.id; }, m);
}

Frame encode(const Message& m) {
  return std::visit([](const auto& x) { return encode(x); }, m);
}

Result<Message, DecodeError> decode_message(const DecodedFrame& f) {
  if (static_cast<std::size_t>(f.type) >= kMessageTypeCount)
    return fail(DecodeError::wrong_message_type, "frame type out of range");
  try {
    return dispatch(f, std::make_index_sequence<kMessageTypeCount>{});
  } catch (const std::exception& e) {
    // yaml-cpp may throw on odd node shapes; callers get a value, never an exception.
    return fail(DecodeError::invalid_value, std::string("header could not be read: ") + e.what());
  }
}

}  // namespace omega::protocol
