#pragma once
// One frame on the wire: a fixed 16-byte prelude, a YAML header, then opaque payload bytes.
// See docs/protocol.md, "Framing".
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace omega::protocol {

inline constexpr std::array<std::uint8_t, 4> kMagic{'O', 'M', 'G', '1'};
inline constexpr std::size_t kPreludeSize = 16;

// Raw frame: the header is kept as text so that encoding never depends on a YAML emitter.
struct Frame {
  std::string header;   // a YAML mapping; our own encoders write canonical JSON (a YAML subset)
  std::string payload;  // opaque bytes
  bool operator==(const Frame&) const = default;
};

// The prelude as bytes: magic, u32 LE header length, u64 LE payload length.
std::array<std::uint8_t, kPreludeSize> encode_prelude(std::uint32_t header_len, std::uint64_t payload_len);

// Appends the frame's bytes to out. The header must fit in a u32 (encoders never come close).
void append_frame(std::string& out, const Frame& frame);
std::string encode_frame(const Frame& frame);

// Little-endian helpers, byte by byte so that host endianness never leaks onto the wire.
void put_u32le(std::uint8_t* p, std::uint32_t v);
void put_u64le(std::uint8_t* p, std::uint64_t v);
std::uint32_t get_u32le(const std::uint8_t* p);
std::uint64_t get_u64le(const std::uint8_t* p);

}  // namespace omega::protocol
