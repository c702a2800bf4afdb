// omega_exr_compare [--rel-tol E] A.exr B.exr: exit 0 when R,G,B and var.* are bit-identical over B's data
// window (B may be a tile of A: then only that window of A is compared), 1 when they differ
// (the first differing pixel is printed), 2 on a read error.
// --rel-tol E: equal means |a - b| <= E * max(|a|, |b|) per channel instead of bit-identical, for
// results whose algebra is exact only to rounding (a merge of partial renders).
// --layer NAME (repeatable, before the files): also compare the float layer NAME.R/G/B (e.g.
// aov.direct, aov.direct.var) the same way; a missing layer is a read error.
// --attr NAME (repeatable, before the files): also require the string attribute NAME (e.g.
// omega.breakdown) to be present in both and equal.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "film/film.h"

namespace {

bool agree(const float* a, const float* b, double tol) {
  if (tol < 0) return std::memcmp(a, b, 3 * sizeof(float)) == 0;
  for (int c = 0; c < 3; ++c)
    if (!(a[c] == b[c] || std::fabs(double(a[c]) - b[c]) <= tol * std::fmax(std::fabs(a[c]), std::fabs(b[c]))))
      return false;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  double tol = -1;  // bit-identical
  if (argc == 5 && std::string(argv[1]) == "--rel-tol") {
    char* end = nullptr;
    tol = std::strtod(argv[2], &end);
    if (*end != '\0' || !(tol >= 0)) {
      std::fprintf(stderr, "omega_exr_compare: --rel-tol wants a number >= 0, not '%s'\n", argv[2]);
      return 2;
    }
    argv += 2;
    argc -= 2;
  }
  std::vector<std::string> layers;
  while (argc >= 5 && std::string(argv[1]) == "--layer") {
    layers.push_back(argv[2]);
    argv += 2;
    argc -= 2;
  }
  std::vector<std::string> attrs;
  while (argc >= 5 && std::string(argv[1]) == "--attr") {
    attrs.push_back(argv[2]);
    argv += 2;
    argc -= 2;
  }
  if (argc != 3) {
    std::fprintf(stderr, "usage: omega_exr_compare [--rel-tol E] FULL.exr PART.exr\n");
    return 2;
  }
  omega::ExrImage a, b;
  std::vector<std::vector<float>> la, lb;
  try {
    a = omega::read_exr(argv[1]);
    b = omega::read_exr(argv[2]);
    for (const std::string& l : layers) {
      la.push_back(omega::read_exr_layer(argv[1], l));
      lb.push_back(omega::read_exr_layer(argv[2], l));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "omega_exr_compare: %s\n", e.what());
    return 2;
  }
  for (const std::string& name : attrs) {
    auto ia = a.attributes.find(name), ib = b.attributes.find(name);
    if (ia == a.attributes.end() || ib == b.attributes.end() || ia->second != ib->second) {
      std::fprintf(stderr, "attribute %s: %s\n", name.c_str(),
                   ia == a.attributes.end() || ib == b.attributes.end() ? "missing" : "differs");
      return 1;
    }
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
      bool same = agree(&a.rgb[ia], &b.rgb[ib], tol) && (a.var.empty() || agree(&a.var[ia], &b.var[ib], tol));
      for (std::size_t l = 0; l < layers.size(); ++l)
        if (!agree(&la[l][ia], &lb[l][ib], tol)) {
          std::fprintf(stderr, "layer %s: pixel (%d, %d) differs\n", layers[l].c_str(), x + b.x0, y + b.y0);
          return 1;
        }
      if (!same) {
        std::fprintf(stderr, "pixel (%d, %d) differs: %.9g %.9g %.9g vs %.9g %.9g %.9g (var %.9g %.9g %.9g vs %.9g %.9g %.9g)\n",
                     x + b.x0, y + b.y0, a.rgb[ia], a.rgb[ia + 1], a.rgb[ia + 2], b.rgb[ib], b.rgb[ib + 1], b.rgb[ib + 2],
                     a.var.empty() ? 0.f : a.var[ia], a.var.empty() ? 0.f : a.var[ia + 1], a.var.empty() ? 0.f : a.var[ia + 2],
                     b.var.empty() ? 0.f : b.var[ib], b.var.empty() ? 0.f : b.var[ib + 1], b.var.empty() ? 0.f : b.var[ib + 2]);
        return 1;
      }
    }
  return 0;
}
