// Fuzzes what the job page's browser sends to `omega view` (client/view_messages.h): every text
// message of the WebSocket goes through decode_view_command. Property: a message that decodes
// re-encodes (canonical JSON) to text that decodes to the same command.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "view_messages.h"

using namespace omega::client;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  auto c = decode_view_command(in);
  if (!c) return 0;
  auto again = decode_view_command(encode_view_command(*c));
  if (!again) std::abort();  // our own encoding must decode
  const ViewCommand& a = *c;
  const ViewCommand& b = *again;
  if (a.kind != b.kind || a.id != b.id || a.job != b.job || a.priority != b.priority || a.user != b.user ||
      a.token != b.token)
    std::abort();
  return 0;
}
