// Fuzzes protocol::FrameDecoder: the input is fed in chunks whose sizes come from its first byte,
// under small limits so that every limit path is reachable. Properties: no crash, no leak, the
// decoder never takes bytes after it failed, and frames respect the limits.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "protocol/frame_decoder.h"

using namespace omega::protocol;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::size_t step = 1 + data[0] % 64;
  DecoderLimits lim;
  lim.max_header_bytes = 4096;
  lim.max_payload_bytes = 1 << 16;
  lim.max_ready_frames = 2;
  for (auto& l : lim.max_payload_for_type)
    if (l > 0) l = 1 << 14;
  FrameDecoder dec(lim);
  std::string_view rest(reinterpret_cast<const char*>(data + 1), size - 1);
  while (!rest.empty()) {
    std::size_t took = dec.feed(rest.substr(0, step));
    if (dec.failed() && took > step) std::abort();
    rest.remove_prefix(took);
    while (auto f = dec.next())
      if (f->payload.size() > lim.max_payload_bytes) std::abort();
    if (dec.failed()) break;
  }
  dec.finish();
  while (dec.next()) {
  }
  return 0;
}
