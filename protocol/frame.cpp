#include "protocol/frame.h"

#include <stdexcept>

namespace omega::protocol {

void put_u32le(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

void put_u64le(std::uint8_t* p, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

std::uint32_t get_u32le(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

std::uint64_t get_u64le(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

std::array<std::uint8_t, kPreludeSize> encode_prelude(std::uint32_t header_len, std::uint64_t payload_len) {
  std::array<std::uint8_t, kPreludeSize> b{};
  for (std::size_t i = 0; i < kMagic.size(); ++i) b[i] = kMagic[i];
  put_u32le(b.data() + 4, header_len);
  put_u64le(b.data() + 8, payload_len);
  return b;
}

void append_frame(std::string& out, const Frame& frame) {
  if (frame.header.size() > UINT32_MAX) throw std::length_error("omega frame header exceeds 4 GiB");
  auto prelude = encode_prelude(static_cast<std::uint32_t>(frame.header.size()), frame.payload.size());
  out.reserve(out.size() + prelude.size() + frame.header.size() + frame.payload.size());
  out.append(reinterpret_cast<const char*>(prelude.data()), prelude.size());
  out += frame.header;
  out += frame.payload;
}

std::string encode_frame(const Frame& frame) {
  std::string out;
  append_frame(out, frame);
  return out;
}

}  // namespace omega::protocol
