#include "daemon/scene_limits.h"

#include <fmt/format.h>

#include "scene/scene_error.h"

namespace omega::daemon {

namespace {
[[noreturn]] void refuse(const std::string& file, const std::string& key, const std::string& what) {
  throw SceneError(file + ":1: " + key + ": " + what);
}
std::string mib(std::uint64_t b) { return fmt::format("{:.0f} MiB", double(b) / (1 << 20)); }
}  // namespace

std::uint64_t film_memory_estimate(const SceneDesc& d) {
  // Each light path expression output is a film of its own, with its snapshots and batch sums.
  return std::uint64_t(d.sensor.film.width) * std::uint64_t(d.sensor.film.height) * kFilmBytesPerPixel *
         (1 + std::uint64_t(d.sensor.film.aovs.size()));
}

void check_scene_limits(const SceneLimits& l, const SceneDesc& d, std::uint64_t asset_bytes, const std::string& file) {
  const auto& f = d.sensor.film;
  if (f.width > l.max_resolution || f.height > l.max_resolution)
    refuse(file, "film", fmt::format("{}x{} pixels is over this daemon's max_resolution ({})", f.width, f.height,
                                     l.max_resolution));
  const std::uint64_t est = film_memory_estimate(d) + asset_bytes * kAssetExpansion;
  if (est > l.max_memory_bytes)
    refuse(file, "film", fmt::format("the scene needs about {} (film {}x{}, {} of assets), over this daemon's "
                                     "max_scene_memory_bytes ({})",
                                     mib(est), f.width, f.height, mib(asset_bytes), mib(l.max_memory_bytes)));
}

void check_built_scene_memory(const SceneLimits& l, const SceneDesc& d, const Scene& s, const std::string& file) {
  std::uint64_t tris = 0;
  for (const auto& sh : s.shapes()) tris += sh.mesh.triangle_count();
  const std::uint64_t est = film_memory_estimate(d) + tris * kBytesPerTriangle;
  if (est > l.max_memory_bytes)
    refuse(file, "shapes", fmt::format("the scene needs about {} ({} triangles, film {}x{}), over this daemon's "
                                       "max_scene_memory_bytes ({})",
                                       mib(est), tris, d.sensor.film.width, d.sensor.film.height,
                                       mib(l.max_memory_bytes)));
}

void check_halt_limits(const SceneLimits& l, const protocol::Halt& h, const std::string& file) {
  if (h.spp && *h.spp > l.max_spp)
    refuse(file, "spp", fmt::format("{} is over this daemon's max_spp ({})", *h.spp, l.max_spp));
  if (h.time_s && *h.time_s > l.max_time_s)
    refuse(file, "time", fmt::format("{} s is over this daemon's max_time_s ({} s)", *h.time_s, l.max_time_s));
}

}  // namespace omega::daemon
