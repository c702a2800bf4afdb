#pragma once
// Floating-point error bounds (Higham's gamma_n) and ulp steps, as used by the one ray spawn routine.
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "math/simd4.h"

namespace omega {

constexpr float kMachineEps = std::numeric_limits<float>::epsilon() * 0.5f;
constexpr float gamma_bound(int n) { return (float(n) * kMachineEps) / (1.f - float(n) * kMachineEps); }

// c ? a : b through a bit mask. GCC turns a ternary on floating-point values back into a
// branch, which mispredicts half the time where c is a coin flip per sample (the concentric
// map's octant, the tent filter's half).
template <class F>
inline F select_bits(bool c, F a, F b) {
    using U = std::conditional_t<sizeof(F) == 4, uint32_t, uint64_t>;
    static_assert(sizeof(F) == sizeof(U));
    const U m = U(0) - U(c);
    return std::bit_cast<F>((std::bit_cast<U>(a) & m) | (std::bit_cast<U>(b) & ~m));
}

inline float next_float_up(float v) {
    if (std::isinf(v) && v > 0.f) return v;
    if (v == -0.f) v = 0.f;
    uint32_t ui = std::bit_cast<uint32_t>(v);
    ui = v >= 0 ? ui + 1 : ui - 1;
    return std::bit_cast<float>(ui);
}
inline float next_float_down(float v) {
    if (std::isinf(v) && v < 0.f) return v;
    if (v == 0.f) v = -0.f;
    uint32_t ui = std::bit_cast<uint32_t>(v);
    ui = v > 0 ? ui - 1 : ui + 1;
    return std::bit_cast<float>(ui);
}

// next_float_up(v) where dir > 0, next_float_down(v) where dir < 0, v where dir is 0, bit for
// bit, by selects: the ray spawn steps each axis by the sign of its offset, which follows the
// surface normal and the direction and so defeats a branch predictor (two spawns per bounce and
// per connection).
inline float next_float_toward(float v, float dir) {
    const uint32_t ui = std::bit_cast<uint32_t>(v);
    const bool up = dir > 0, negative = (ui >> 31) != 0;
    // Away from zero where the step and v's sign agree; zero of either sign steps to the
    // smallest denormal of the step's sign; the infinity in the step's direction stays.
    uint32_t r = up != negative ? ui + 1 : ui - 1;
    r = (ui & 0x7fffffffu) == 0 ? (up ? 1u : 0x80000001u) : r;
    r = (ui & 0x7fffffffu) == 0x7f800000u && up != negative ? ui : r;
    r = dir == 0 ? ui : r;
    return std::bit_cast<float>(r);
}

// next_float_toward on four lanes of bits at once, the same selects bit for bit: the ray spawn
// steps all three axes of a point, and the scalar form took ~30 instructions an axis (7% of the
// path tracer's instructions went to offset_ray_origin).
inline U4 next_float_toward4(U4 ui, F4 dir) {
    const U4 up = (U4)(dir > F4{});                // all ones where dir > 0
    const U4 negative = (U4)((I4)ui >> 31);        // all ones where v's sign bit is set
    const U4 away = up ^ negative;                 // all ones where the step leaves zero behind
    U4 r = ui - 1u - 2u * away;                    // ui + 1 away from zero, ui - 1 towards it
    const U4 magnitude = ui & 0x7fffffffu;
    const U4 zero = (U4)(magnitude == 0u);
    r = (zero & (0x80000001u & ~(up & 0x80000000u))) | (~zero & r);
    const U4 keep = ((U4)(magnitude == 0x7f800000u) & away) | (U4)(dir == F4{});
    return (keep & ui) | (~keep & r);
}

}  // namespace omega
