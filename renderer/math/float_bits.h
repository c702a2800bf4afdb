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

}  // namespace omega
