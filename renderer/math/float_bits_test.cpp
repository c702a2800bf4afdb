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

// The four-lane form must equal the scalar one on every lane, for every kind of value and step
// (zeros of both signs, infinities, NaNs, denormals; steps up, down, zero and NaN).
TEST(FloatBits, NextFloatToward4EqualsTheScalarFormOnEveryLane) {
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<float> values = {0.f, -0.f, 1.f, -1.f, inf, -inf, nan, -nan, std::numeric_limits<float>::denorm_min(),
                                 -std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::max(),
                                 -std::numeric_limits<float>::max(), std::numeric_limits<float>::min(), 1e-30f, -3.5e7f};
    const std::vector<float> steps = {0.25f, -1e-30f, 0.f, -0.f, inf, -inf, nan, -nan, 1e-45f, -1e-45f};
    Rng rng(5, 0);
    for (int i = 0; i < 20000; ++i) values.push_back(std::bit_cast<float>(rng.next_u32()));
    long long checked = 0;
    for (size_t i = 0; i < values.size(); ++i) {
        const float v[4] = {values[i], values[(i + 1) % values.size()], values[(i * 7 + 3) % values.size()], -values[i]};
        for (size_t k = 0; k < steps.size(); ++k) {
            const float dir[4] = {steps[k], steps[(k + 1) % steps.size()], steps[(k + i) % steps.size()],
                                  steps[(k * 3 + i) % steps.size()]};
            const U4 r = next_float_toward4(U4{bits(v[0]), bits(v[1]), bits(v[2]), bits(v[3])},
                                            F4{dir[0], dir[1], dir[2], dir[3]});
            for (int lane = 0; lane < 4; ++lane, ++checked)
                ASSERT_EQ(r[lane], bits(next_float_toward(v[lane], dir[lane]))) << v[lane] << " toward " << dir[lane];
        }
    }
    EXPECT_GT(checked, 800000);
}

// select_bits is the ternary, bit for bit: signed zeros, infinities and NaN payloads pass through.
TEST(FloatBits, SelectBitsIsTheTernaryBitForBit) {
    const float fv[] = {0.f, -0.f, 1.5f, -2.f, std::numeric_limits<float>::infinity(),
                        std::bit_cast<float>(0x7fc01234u), std::bit_cast<float>(0xffa00001u),
                        std::numeric_limits<float>::denorm_min()};
    for (float a : fv)
        for (float b : fv)
            for (bool c : {false, true}) EXPECT_EQ(bits(select_bits(c, a, b)), bits(c ? a : b));
    const double dv[] = {0.0, -0.0, 1e300, -3.25, std::bit_cast<double>(0x7ff8000000abcdefull),
                         std::numeric_limits<double>::denorm_min()};
    for (double a : dv)
        for (double b : dv)
            for (bool c : {false, true})
                EXPECT_EQ(std::bit_cast<uint64_t>(select_bits(c, a, b)), std::bit_cast<uint64_t>(c ? a : b));
}

}  // namespace
}  // namespace omega
