#pragma once
// Tabulated complex IOR of common metals, reduced to RGB, for `material: Au|Ag|Cu|Al`.
#include <optional>
#include <string_view>
#include <utility>

#include "math/vec.h"

namespace omega {

// Returns (eta, k) for a metal name such as "Au", or nullopt if the name is unknown.
std::optional<std::pair<Rgb, Rgb>> named_metal_ior(std::string_view name);

}  // namespace omega
