// Fuzzes what the job page's browser sends to `omega view` (client/view_messages.h): every text
// message of the WebSocket goes through decode_view_command, and the upgrade request's Host and
// Origin headers through websocket_upgrade_allowed (the input's first two lines). Properties: a
// message that decodes re-encodes (canonical JSON) to text that decodes to the same command; an
// upgrade is allowed only for a Host that is a loopback name and an optional numeric port.
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
      // Allowed means a loopback name and at most ":digits" after it, nothing else.
      std::size_t n = 0;
      if (host.rfind("localhost", 0) == 0) n = 9;
      else if (host.rfind("[::1]", 0) == 0) n = 5;
      else if (host.rfind("127.", 0) == 0) n = host.find_first_not_of("0123456789.");
      else std::abort();
      const std::string rest = n == std::string::npos ? std::string() : host.substr(n);
      if (!rest.empty() && (rest[0] != ':' || rest.size() == 1 || rest.size() > 6 ||
                            rest.find_first_not_of("0123456789", 1) != std::string::npos))
        std::abort();
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
