#include "protocol/frame_decoder.h"

#include <algorithm>

namespace omega::protocol {

namespace {
// Growth step for payload buffers: memory follows the bytes that actually arrived.
constexpr std::size_t kPayloadChunk = 64 * 1024;
}  // namespace

std::array<std::uint64_t, kMessageTypeCount> DecoderLimits::default_type_limits() {
  std::array<std::uint64_t, kMessageTypeCount> a{};
  a[static_cast<std::size_t>(MessageType::submit)] = 64ull << 20;
  a[static_cast<std::size_t>(MessageType::asset)] = 1ull << 30;
  a[static_cast<std::size_t>(MessageType::tile)] = 16ull << 20;
  a[static_cast<std::size_t>(MessageType::image)] = 1ull << 30;
  a[static_cast<std::size_t>(MessageType::work_unit)] = 64ull << 20;   // a scene, as submit
  a[static_cast<std::size_t>(MessageType::unit_result)] = 1ull << 30;  // a part, as image
  return a;
}

std::uint64_t DecoderLimits::payload_limit(MessageType t) const {
  return std::min(max_payload_bytes, max_payload_for_type[static_cast<std::size_t>(t)]);
}

FrameDecoder::FrameDecoder(DecoderLimits limits) : limits_(limits) {
  if (limits_.max_ready_frames == 0) limits_.max_ready_frames = 1;
}

void FrameDecoder::set_error(FrameError e, std::string msg) {
  if (!error_) error_ = Failure<FrameError>{e, std::move(msg)};
  // Release buffers: a failed decoder is never used again.
  header_ = std::string();
  payload_ = std::string();
}

std::size_t FrameDecoder::feed(std::string_view bytes) noexcept {
  return feed(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
}

std::size_t FrameDecoder::feed(std::span<const std::uint8_t> bytes) noexcept {
  std::size_t used = 0;
  try {
    while (used < bytes.size() && !error_ && ready_.size() < limits_.max_ready_frames) {
      auto rest = bytes.subspan(used);
      switch (stage_) {
        case Stage::prelude: {
          std::uint8_t b = rest[0];
          // Check the magic byte by byte so garbage is refused at its first wrong byte.
          if (prelude_len_ < kMagic.size() && b != kMagic[prelude_len_]) {
            set_error(FrameError::bad_magic, "bad magic: frame does not start with OMG1");
            return used;
          }
          prelude_[prelude_len_++] = b;
          ++used;
          if (prelude_len_ == kPreludeSize) prelude_complete();
          break;
        }
        case Stage::header: {
          std::size_t n = std::min<std::size_t>(rest.size(), header_len_ - header_.size());
          header_.append(reinterpret_cast<const char*>(rest.data()), n);
          used += n;
          if (header_.size() == header_len_) header_complete();
          break;
        }
        case Stage::payload: {
          std::uint64_t want = payload_len_ - payload_.size();
          std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(rest.size(), want));
          if (payload_.capacity() < payload_.size() + n) {
            std::uint64_t grow = std::max<std::uint64_t>(payload_.size() + n, payload_.capacity() * 2);
            payload_.reserve(static_cast<std::size_t>(std::min<std::uint64_t>(grow, payload_len_)));
          }
          payload_.append(reinterpret_cast<const char*>(rest.data()), n);
          used += n;
          if (payload_.size() == payload_len_) payload_complete();
          break;
        }
      }
    }
  } catch (const std::exception& e) {
    // Only allocation can get here (limits bound every size); fail instead of throwing.
    set_error(FrameError::payload_too_large, std::string("out of memory while decoding: ") + e.what());
  }
  return used;
}

void FrameDecoder::prelude_complete() {
  header_len_ = get_u32le(prelude_.data() + 4);
  payload_len_ = get_u64le(prelude_.data() + 8);
  if (header_len_ > limits_.max_header_bytes) {
    set_error(FrameError::header_too_large, "header of " + std::to_string(header_len_) +
                                                " bytes exceeds the limit of " +
                                                std::to_string(limits_.max_header_bytes));
    return;
  }
  if (payload_len_ > limits_.max_payload_bytes) {
    set_error(FrameError::payload_too_large, "payload of " + std::to_string(payload_len_) +
                                                 " bytes exceeds the limit of " +
                                                 std::to_string(limits_.max_payload_bytes));
    return;
  }
  header_.clear();
  header_.reserve(header_len_);
  stage_ = Stage::header;
  if (header_len_ == 0) header_complete();
}

void FrameDecoder::header_complete() {
  try {
    auto r = parse_header(header_);
    if (!r) {
      set_error(r.code(), r.message());
      return;
    }
    parsed_.emplace(r.value());
  } catch (const std::exception& e) {
    set_error(FrameError::header_not_yaml, std::string("header is not valid YAML: ") + e.what());
    return;
  }
  std::uint64_t limit = limits_.payload_limit(parsed_->type);
  if (payload_len_ > limit) {
    set_error(FrameError::payload_too_large_for_type,
              std::string(to_string(parsed_->type)) + " frame with a payload of " +
                  std::to_string(payload_len_) + " bytes exceeds its limit of " + std::to_string(limit));
    return;
  }
  header_ = std::string();
  payload_.clear();
  payload_.reserve(static_cast<std::size_t>(std::min<std::uint64_t>(payload_len_, kPayloadChunk)));
  stage_ = Stage::payload;
  if (payload_len_ == 0) payload_complete();
}

void FrameDecoder::payload_complete() {
  ready_.emplace_back(parsed_->type, parsed_->id, parsed_->header, std::move(payload_));
  parsed_.reset();
  payload_ = std::string();
  prelude_len_ = 0;
  stage_ = Stage::prelude;
}

std::optional<DecodedFrame> FrameDecoder::next() {
  if (ready_.empty()) return std::nullopt;
  DecodedFrame f = std::move(ready_.front());
  ready_.pop_front();
  return f;
}

void FrameDecoder::finish() noexcept {
  if (!error_ && !at_frame_boundary())
    set_error(FrameError::truncated, "stream ended inside a frame");
}

}  // namespace omega::protocol
