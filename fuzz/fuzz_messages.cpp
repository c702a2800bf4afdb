// Fuzzes every message decoder through protocol::decode_message. The input is a frame's header
// text (a YAML mapping), then optionally "\0" and the payload; the frame is decoded by the real
// FrameDecoder. Property: a message that decodes re-encodes to a frame that decodes to the same
// message (the canonical form round-trips).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "protocol/frame_decoder.h"
#include "protocol/messages.h"

using namespace omega::protocol;

namespace {
std::optional<DecodedFrame> decode_one(const std::string& bytes) {
  FrameDecoder dec;
  dec.feed(std::string_view(bytes));
  dec.finish();
  return dec.next();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string_view in(reinterpret_cast<const char*>(data), size);
  std::size_t nul = in.find('\0');
  Frame frame{std::string(in.substr(0, nul)), nul == std::string_view::npos ? std::string() : std::string(in.substr(nul + 1))};
  auto f = decode_one(encode_frame(frame));
  if (!f) return 0;
  auto m = decode_message(*f);
  if (!m) return 0;
  auto again = decode_one(encode_frame(encode(*m)));
  if (!again) std::abort();  // our own encoding must be a frame
  auto m2 = decode_message(*again);
  if (!m2 || !(*m2 == *m)) std::abort();
  return 0;
}
