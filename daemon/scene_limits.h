#pragma once
// Per-job resource limits checked while a submit is validated (background thread; pure
// functions). Each throws SceneError with a "NAME.yaml:1: key: what" message naming the config
// key, so the client gets `error scene_invalid` with a clear reason.
#include <cstdint>
#include <string>

#include "protocol/messages.h"
#include "scene/scene.h"
#include "scene/scene_desc.h"

namespace omega::daemon {

struct SceneLimits {
  int max_resolution = 16384;
  std::uint64_t max_spp = 1ull << 24;
  double max_time_s = 7 * 86400.0;
  std::uint64_t max_memory_bytes = 8ull << 30;
};

// Memory a film of w x h costs the daemon: the live film's statistics plus the snapshot, the
// checkpoint buffer and the encoded image it keeps around (a deliberate over-estimate).
inline constexpr std::uint64_t kFilmBytesPerPixel = 256;
// A triangle once built: positions, normals, indices, face normal, area table and Embree's BVH.
inline constexpr std::uint64_t kBytesPerTriangle = 192;
// Before the build, a mesh file may expand this much when parsed (text OBJ/PLY to floats + BVH).
inline constexpr std::uint64_t kAssetExpansion = 8;

std::uint64_t film_memory_estimate(const SceneDesc& d);

// Resolution, and film + assets memory, before the scene is built.
void check_scene_limits(const SceneLimits& l, const SceneDesc& d, std::uint64_t asset_bytes, const std::string& file);
// Film + triangles once built.
void check_built_scene_memory(const SceneLimits& l, const SceneDesc& d, const Scene& s, const std::string& file);
// The effective halt (after the scene's own defaults).
void check_halt_limits(const SceneLimits& l, const protocol::Halt& h, const std::string& file);

}  // namespace omega::daemon
