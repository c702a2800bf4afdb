#pragma once
// Floating-point error bounds (Higham's gamma_n) and ulp steps, as used by the one ray spawn routine.
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace omega {

constexpr float kMachineEps = std::numeric_limits<float>::epsilon() * 0.5f;
constexpr float gamma_bound(int n) { return (float(n) * kMachineEps) / (1.f - float(n) * kMachineEps); }

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

}  // namespace omega
