#pragma once
// Incremental frame decoder: bytes go in with any split, complete frames come out. Every length
// is checked against DecoderLimits before memory is set aside for it, and memory for a payload
// grows only as its bytes arrive, so a peer that lies about a length costs nothing.
#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "protocol/errors.h"
#include "protocol/frame.h"
#include "protocol/header.h"
#include "protocol/message_type.h"
#include "protocol/result.h"

namespace omega::protocol {

struct DecoderLimits {
  std::uint32_t max_header_bytes = 1u << 20;        // 1 MiB
  std::uint64_t max_payload_bytes = 1ull << 30;     // 1 GiB, caps every type
  std::array<std::uint64_t, kMessageTypeCount> max_payload_for_type = default_type_limits();
  std::size_t max_ready_frames = 8;                 // decoded frames held before feed() pauses

  void set_payload_limit(MessageType t, std::uint64_t n) {
    max_payload_for_type[static_cast<std::size_t>(t)] = n;
  }
  std::uint64_t payload_limit(MessageType t) const;
  // submit and work_unit 64 MiB, asset, image and unit_result 1 GiB, tile 16 MiB; 0 for types
  // without payload.
  static std::array<std::uint64_t, kMessageTypeCount> default_type_limits();
};

class FrameDecoder {
 public:
  explicit FrameDecoder(DecoderLimits limits = {});

  // Consumes bytes and returns how many it took. It takes fewer than offered only when
  // max_ready_frames frames wait in next(), or when the decoder has failed. Never throws.
  std::size_t feed(std::span<const std::uint8_t> bytes) noexcept;
  std::size_t feed(std::string_view bytes) noexcept;

  // The oldest complete frame, if any. Frames decoded before an error are still delivered.
  std::optional<DecodedFrame> next();

  // Call at end of stream: a frame cut short becomes a `truncated` error.
  void finish() noexcept;

  bool failed() const { return error_.has_value(); }
  const std::optional<Failure<FrameError>>& error() const { return error_; }
  bool at_frame_boundary() const { return stage_ == Stage::prelude && prelude_len_ == 0; }
  std::size_t ready_frames() const { return ready_.size(); }
  const DecoderLimits& limits() const { return limits_; }

 private:
  enum class Stage { prelude, header, payload };
  void set_error(FrameError e, std::string msg);
  void prelude_complete();
  void header_complete();
  void payload_complete();

  DecoderLimits limits_;
  Stage stage_ = Stage::prelude;
  std::array<std::uint8_t, kPreludeSize> prelude_{};
  std::size_t prelude_len_ = 0;
  std::uint32_t header_len_ = 0;
  std::uint64_t payload_len_ = 0;
  std::string header_;
  std::optional<ParsedHeader> parsed_;
  std::string payload_;
  std::deque<DecodedFrame> ready_;
  std::optional<Failure<FrameError>> error_;
};

}  // namespace omega::protocol
