#pragma once
// Complex indices of refraction of common metals, reduced to RGB.
#include <optional>
#include <string_view>
#include <utility>

#include "math/vec.h"

namespace omega {

// Returns (eta, k) for "Au", "Ag", "Cu", "Al" (case-sensitive, Mitsuba's names), or nullopt.
std::optional<std::pair<Rgb, Rgb>> named_metal_ior(std::string_view name);

}  // namespace omega
