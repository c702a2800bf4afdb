// Fuzzes what the job page's browser sends to `omega view` (client/view_messages.h): every text
// message of the WebSocket goes through decode_view_command, and the upgrade request's Host and
// Origin headers through websocket_upgrade_allowed (the input's first two lines). Properties: a
// message that decodes re-encodes (canonical JSON) to text that decodes to the same command; an
// upgrade is allowed only for a Host that starts with a loopback name.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "view_messages.h"

using namespace omega::client;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  {
    const auto nl = in.find('\n');
    const std::string host(in.substr(0, nl));
    const std::string origin(nl == std::string_view::npos ? std::string_view() : in.substr(nl + 1));
    const bool no_origin = nl == std::string_view::npos;
    if (host.find('\0') == std::string::npos && origin.find('\0') == std::string::npos &&
        websocket_upgrade_allowed(host.c_str(), no_origin ? nullptr : origin.c_str())) {
      const bool loopback = host.rfind("localhost", 0) == 0 || host.rfind("127.", 0) == 0 || host.rfind("[::1]", 0) == 0 || host == "::1";
      if (!loopback) std::abort();
      if (!no_origin && origin != "http://" + host) std::abort();
    }
  }
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
