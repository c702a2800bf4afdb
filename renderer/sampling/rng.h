#pragma once
// Counter-based random numbers. The stream for sample `index` of pixel `pixel` depends only on
// (seed, pixel, index), so images are identical for any thread count and tile order, and sample
// ranges rendered apart (other machines, before and after a restart) merge exactly.
#include <cstdint>

namespace omega {

// Murmur3's 64-bit finaliser: a bijective avalanche mix.
constexpr uint64_t mix64(uint64_t k) {
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdULL;
    k ^= k >> 33;
    k *= 0xc4ceb9fe1a85ec53ULL;
    k ^= k >> 33;
    return k;
}

constexpr uint64_t hash3(uint64_t a, uint64_t b, uint64_t c) {
    return mix64(mix64(mix64(a ^ 0x9e3779b97f4a7c15ULL) ^ b) + c * 0xbf58476d1ce4e5b9ULL);
}

// PCG32 (O'Neill): small state, good statistical quality, cheap to seed per sample.
class Rng {
public:
    Rng() : Rng(0, 0) {}
    Rng(uint64_t seq_index, uint64_t offset) { seed(seq_index, offset); }

    // One independent stream per (seed, stream, index): `stream` is a pixel or a light-path id.
    static Rng for_sample(uint64_t seed, uint64_t stream, uint64_t index) {
        return Rng(hash3(seed, stream, index), mix64(index ^ (stream << 1)));
    }

    void seed(uint64_t seq_index, uint64_t offset) {
        state_ = 0u;
        inc_ = (seq_index << 1u) | 1u;
        next_u32();
        state_ += offset;
        next_u32();
    }
    uint32_t next_u32() {
        uint64_t old = state_;
        state_ = old * 0x5851f42d4c957f2dULL + inc_;
        uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
        uint32_t rot = uint32_t(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
    }
    // Uniform in [0, 1): 24 random mantissa bits, never rounds up to 1.
    float next_1d() { return float(next_u32() >> 8) * 0x1p-24f; }
    double next_1d_double() { return double((uint64_t(next_u32()) << 21) ^ next_u32()) * 0x1p-53; }

private:
    uint64_t state_{}, inc_{};
};

}  // namespace omega
