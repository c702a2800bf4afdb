// omega_exr_compare A.exr B.exr: exit 0 when R,G,B and var.* are bit-identical over B's data
// window (B may be a tile of A: then only that window of A is compared), 1 when they differ
// (the first differing pixel is printed), 2 on a read error.
#include <cstdio>
#include <cstring>
#include <exception>

#include "film/film.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: omega_exr_compare FULL.exr PART.exr\n");
    return 2;
  }
  omega::ExrImage a, b;
  try {
    a = omega::read_exr(argv[1]);
    b = omega::read_exr(argv[2]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "omega_exr_compare: %s\n", e.what());
    return 2;
  }
  if (b.x0 < a.x0 || b.y0 < a.y0 || b.x0 + b.width > a.x0 + a.width || b.y0 + b.height > a.y0 + a.height) {
    std::fprintf(stderr, "data window of %s is not inside that of %s\n", argv[2], argv[1]);
    return 1;
  }
  if (a.var.empty() != b.var.empty()) {
    std::fprintf(stderr, "one image has variance channels, the other not\n");
    return 1;
  }
  for (int y = 0; y < b.height; ++y)
    for (int x = 0; x < b.width; ++x) {
      std::size_t ib = 3 * (std::size_t(y) * b.width + x);
      std::size_t ia = 3 * (std::size_t(y + b.y0 - a.y0) * a.width + (x + b.x0 - a.x0));
      bool same = std::memcmp(&a.rgb[ia], &b.rgb[ib], 3 * sizeof(float)) == 0 &&
                  (a.var.empty() || std::memcmp(&a.var[ia], &b.var[ib], 3 * sizeof(float)) == 0);
      if (!same) {
        std::fprintf(stderr, "pixel (%d, %d) differs: %.9g %.9g %.9g vs %.9g %.9g %.9g\n", x + b.x0, y + b.y0,
                     a.rgb[ia], a.rgb[ia + 1], a.rgb[ia + 2], b.rgb[ib], b.rgb[ib + 1], b.rgb[ib + 2]);
        return 1;
      }
    }
  return 0;
}
