// omega_frame_echo: reads frames on stdin, decodes each into its typed message, encodes it
// again and writes it to stdout. Errors go to stderr as "frame_error CODE: message" or
// "decode_error CODE: message" with exit status 1. Used by the Python interop test.
#include <cstdio>
#include <string>

#include "protocol/frame_decoder.h"
#include "protocol/messages.h"

using namespace omega::protocol;

int main() {
  FrameDecoder dec;
  std::string chunk(65536, '\0');
  bool eof = false;
  std::string pending;  // bytes read but not yet taken by the decoder
  while (true) {
    if (pending.empty() && !eof) {
      std::size_t n = std::fread(chunk.data(), 1, chunk.size(), stdin);
      if (n == 0) eof = true;
      pending.assign(chunk.data(), n);
    }
    std::size_t used = dec.feed(pending);
    pending.erase(0, used);
    while (auto f = dec.next()) {
      auto m = decode_message(*f);
      if (!m) {
        std::fprintf(stderr, "decode_error %s: %s\n", std::string(to_string(m.code())).c_str(),
                     m.message().c_str());
        return 1;
      }
      std::string out = encode_frame(encode(*m));
      std::fwrite(out.data(), 1, out.size(), stdout);
    }
    if (dec.failed()) break;
    if (eof && pending.empty()) {
      dec.finish();
      break;
    }
  }
  std::fflush(stdout);
  if (dec.failed()) {
    std::fprintf(stderr, "frame_error %s: %s\n", std::string(to_string(dec.error()->code)).c_str(),
                 dec.error()->message.c_str());
    return 1;
  }
  return 0;
}
