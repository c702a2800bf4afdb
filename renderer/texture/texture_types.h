#pragma once
// The small value types a bitmap reference carries, shared by the scene description (parser,
// writer, importer) and the texture lookup itself.
#include <array>
#include <cstdint>

#include "math/vec.h"

namespace omega {

// Mitsuba's filter_type: bilinear interpolation between texel centres, or the nearest texel.
enum class TexFilter : uint8_t { Bilinear, Nearest };
// Mitsuba's wrap_mode for uv outside [0, 1].
enum class TexWrap : uint8_t { Repeat, Mirror, Clamp };

// Mitsuba's to_uv: a 2D affine map applied to the surface uv before the lookup,
// u' = m[0] u + m[1] v + m[2], v' = m[3] u + m[4] v + m[5].
struct UvTransform {
    std::array<float, 6> m{1, 0, 0, 0, 1, 0};
    Vec2 apply(Vec2 uv) const { return {m[0] * uv.x + m[1] * uv.y + m[2], m[3] * uv.x + m[4] * uv.y + m[5]}; }
    bool is_identity() const { return m == UvTransform{}.m; }
    // This map applied after `first`.
    UvTransform after(const UvTransform& first) const {
        const auto& a = m;
        const auto& b = first.m;
        return {{a[0] * b[0] + a[1] * b[3], a[0] * b[1] + a[1] * b[4], a[0] * b[2] + a[1] * b[5] + a[2],
                 a[3] * b[0] + a[4] * b[3], a[3] * b[1] + a[4] * b[4], a[3] * b[2] + a[4] * b[5] + a[5]}};
    }
    bool operator==(const UvTransform&) const = default;
};

}  // namespace omega
