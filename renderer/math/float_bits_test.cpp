#include "math/float_bits.h"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "sampling/rng.h"

namespace omega {
namespace {

uint32_t bits(float v) { return std::bit_cast<uint32_t>(v); }

// The select form must equal the branching pair bit for bit, or every spawned ray would move.
TEST(FloatBits, NextFloatTowardEqualsUpAndDown) {
    const float inf = std::numeric_limits<float>::infinity();
    std::vector<float> values = {0.f, -0.f, 1.f, -1.f, inf, -inf, std::numeric_limits<float>::denorm_min(),
                                 -std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::max(),
                                 -std::numeric_limits<float>::max(), std::numeric_limits<float>::min(), 1e-30f, -3.5e7f};
    Rng rng(3, 0);
    for (int i = 0; i < 100000; ++i) {
        float v = std::bit_cast<float>(rng.next_u32());
        if (std::isfinite(v)) values.push_back(v);
    }
    for (float v : values) {
        EXPECT_EQ(bits(next_float_toward(v, 0.25f)), bits(next_float_up(v))) << v;
        EXPECT_EQ(bits(next_float_toward(v, -1e-30f)), bits(next_float_down(v))) << v;
        EXPECT_EQ(bits(next_float_toward(v, 0.f)), bits(v)) << v;
        EXPECT_EQ(bits(next_float_toward(v, -0.f)), bits(v)) << v;
    }
}

}  // namespace
}  // namespace omega
