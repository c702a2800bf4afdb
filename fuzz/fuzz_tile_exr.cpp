// Fuzzes the client's tile path: a `tile` payload (EXR bytes from the network) applied to a
// TileCanvas. The first 8 input bytes choose the rect; the rest is the EXR. Bad input must be a
// ClientError (exit 1), never a crash.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "client_error.h"
#include "tile_canvas.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 8) return 0;
  omega::protocol::Tile t;
  t.id = 1;
  t.job = 1;
  std::uint16_t r[4];
  std::memcpy(r, data, 8);
  t.rect = {r[0] % 512u, r[1] % 512u, r[0] % 512u + 1 + r[2] % 64u, r[1] % 512u + 1 + r[3] % 64u};
  t.pass = 1;
  t.spp = 1;
  t.version = 1;
  t.exr.assign(reinterpret_cast<const char*>(data + 8), size - 8);
  omega::client::TileCanvas canvas;
  try {
    canvas.apply(t);
  } catch (const omega::client::ClientError&) {
  }
  return 0;
}
