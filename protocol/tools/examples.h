#pragma once
// One example of every message, as shown in docs/protocol.md, and the hex dump format used there.
#include <string>
#include <string_view>
#include <vector>

#include "protocol/messages.h"

namespace omega::protocol::examples {

struct Example {
  std::string title;
  Message message;
};

std::vector<Example> all();
// hexdump -C layout: offset, 16 bytes in two groups of 8, then the printable ASCII.
std::string hex_dump(std::string_view bytes);
// The fenced block that docs/protocol.md must contain for this example.
std::string markdown_block(const Example& e);

inline constexpr std::string_view kAuthToken = "s3cret";  // the token behind the auth example

}  // namespace omega::protocol::examples
