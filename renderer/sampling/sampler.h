#pragma once
// The integrators' source of sample values: a closed set of two generators behind one value type
// (a branch on the type, no virtual call).
//
// - independent: today's PCG32 stream Rng::for_sample(seed, stream, index), drawn in call order.
//   start_dimension() is ignored, so images made with it are bit-identical to those made before
//   the sampler existed.
// - sobol: padded, shuffled, Owen-scrambled 2D Sobol' points (Burley 2020, "Practical Hash-based
//   Owen Scrambling", JCGT 9(4); the hash is Vegdahl's 2021 improvement of Laine-Karras). Each
//   dimension pair d of sample `index` of `stream` (a pixel) is
//       i' = owen_index(index, h(seed, stream, d))            (shuffles the samples of the pair)
//       (x, y) = (owen(sobol0(i'), h0), owen(sobol1(i'), h1))
//   Only Sobol' dimensions 0 and 1 are needed (no direction-number table), so there is no limit
//   on the number of dimensions; dimensions are independent of each other through their hashes.
//   The index shuffle is an Owen scramble of the index's bits from the top, so every aligned
//   block of 2^m indices maps onto an aligned block of 2^m Sobol' indices: any aligned prefix or
//   range of 2^m samples of one pixel is a (0,m,2)-net in every pair, whatever spp ends up being.
//   That keeps sample ranges splittable and resumable: a sample's value depends only on
//   (seed, stream, index, dimension), never on which other samples were drawn.
//
// Dimension layout (namespace dims): an integrator calls start_dimension() before each decision
// so that dimension d means the same decision in every sample of a pixel (camera, per bounce
// blocks, light subpath, BDPT connections). Beyond kMaxDepth bounces the sobol sampler draws
// hashed independent numbers (its own PCG stream): those paths are rare after Russian roulette
// and gain nothing from stratification.
#include <cstdint>

#include "math/vec.h"
#include "sampling/rng.h"
#include "sampling/sampler_type.h"

namespace omega {

namespace dims {

inline constexpr int kMaxDepth = 64;           // bounce blocks with Sobol' dimensions
inline constexpr uint32_t kBeyond = ~0u;       // past the layout: independent numbers

inline constexpr uint32_t kFilm = 0;           // 2D: position in the pixel
inline constexpr uint32_t kLens = 2;           // 2D: point on the lens
// A bounce block, per vertex of a walk: offsets inside the block.
inline constexpr uint32_t kBlock = 8;
inline constexpr uint32_t kDirect = 0;         // 1D light selection, then 2D point on the light
inline constexpr uint32_t kScatter = 3;        // 1D lobe, then 2D direction
inline constexpr uint32_t kRoulette = 6;       // 1D Russian roulette
inline constexpr uint32_t kCameraWalk = 4;
inline constexpr uint32_t kEmit = kCameraWalk + kBlock * kMaxDepth;  // 1D light, 2D position, 2D direction
inline constexpr uint32_t kLightWalk = kEmit + kBlock;
inline constexpr uint32_t kConnectLight = kLightWalk + kBlock * kMaxDepth;  // s = 1: 3 dims per t
inline constexpr uint32_t kConnectSensor = kConnectLight + 4 * kMaxDepth;   // t = 1: 2 dims per s
// The planar-mirror connector (pathspace/mirror_connector.h), per vertex and mirror: a light
// sample through the mirror (3 dims), a lens sample through it (2 dims).
inline constexpr uint32_t kMirrorSlots = 4;
inline constexpr uint32_t kMirrorLight = kConnectSensor + 2 * kMaxDepth;
inline constexpr uint32_t kMirrorSensor = kMirrorLight + 3 * kMirrorSlots * kMaxDepth;

// `vertex` counts vertices of the walk before this one's scattering (the path tracer's edges k).
constexpr uint32_t camera_walk(int vertex, uint32_t slot) {
    return vertex >= 0 && vertex < kMaxDepth ? kCameraWalk + kBlock * uint32_t(vertex) + slot : kBeyond;
}
constexpr uint32_t light_walk(int vertex, uint32_t slot) {
    return vertex >= 0 && vertex < kMaxDepth ? kLightWalk + kBlock * uint32_t(vertex) + slot : kBeyond;
}
// BDPT strategy (1, t): the light sample from camera vertex t - 1.
constexpr uint32_t connect_light(int t) { return t >= 0 && t < kMaxDepth ? kConnectLight + 4 * uint32_t(t) : kBeyond; }
// Strategy (s, 1): the lens sample seen from light vertex s - 1.
constexpr uint32_t connect_sensor(int s) { return s >= 0 && s < kMaxDepth ? kConnectSensor + 2 * uint32_t(s) : kBeyond; }
// Next-event estimation through mirror `m` from camera-walk vertex `vertex`.
constexpr uint32_t mirror_light(int vertex, int m) {
    return vertex >= 0 && vertex < kMaxDepth ? kMirrorLight + 3 * (kMirrorSlots * uint32_t(vertex) + uint32_t(m)) : kBeyond;
}
// Strategy (s, 1) through mirror `m`.
constexpr uint32_t mirror_sensor(int s, int m) {
    return s >= 0 && s < kMaxDepth ? kMirrorSensor + 2 * (kMirrorSlots * uint32_t(s) + uint32_t(m)) : kBeyond;
}

}  // namespace dims

namespace sobol {

constexpr uint32_t reverse_bits(uint32_t x) {
    x = __builtin_bswap32(x);
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    return ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
}

// A random permutation of 32-bit words in which bit j changes only as a function of bits below j
// (even multipliers, one odd one, an add): in bit-reversed order that is an Owen scramble.
constexpr uint32_t laine_karras(uint32_t x, uint32_t seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

// Owen scrambling of a 0.32 fixed-point value (most significant digit first).
constexpr uint32_t owen(uint32_t x, uint32_t seed) { return reverse_bits(laine_karras(reverse_bits(x), seed)); }

// Sobol' dimension 0 (van der Corput) and 1 (primitive polynomial x + 1), 0.32 fixed point.
constexpr uint32_t dim0(uint32_t i) { return reverse_bits(i); }
// Dimension 1 by its generator matrix, column j = v_j (v_0 = 2^31, v_{j+1} = v_j ^ v_j >> 1),
// one bit of the index at a time: the reference for the table below.
constexpr uint32_t dim1_by_bits(uint32_t i) {
    uint32_t r = 0;
    for (uint32_t v = 1u << 31; i; i >>= 1, v ^= v >> 1)
        if (i & 1u) r ^= v;
    return r;
}
// reverse_bits(dim1(i)) a byte of the index at a time (4 KiB): the shuffled indices have all 32
// bits set at random, so the bit loop's 32 unpredictable branches would cost more than the rest
// of a draw; bit-reversed, the value goes straight into the scramble (see owen()).
struct Dim1Table {
    uint32_t t[4][256];
    constexpr Dim1Table() : t{} {
        for (uint32_t k = 0; k < 4; ++k)
            for (uint32_t b = 0; b < 256; ++b) t[k][b] = reverse_bits(dim1_by_bits(b << (8 * k)));
    }
};
inline constexpr Dim1Table kDim1Reversed{};
constexpr uint32_t dim1_reversed(uint32_t i) {
    const auto& t = kDim1Reversed.t;
    return t[0][i & 0xff] ^ t[1][(i >> 8) & 0xff] ^ t[2][(i >> 16) & 0xff] ^ t[3][i >> 24];
}
// The shuffle's output comes bit-reversed (z = LK(rev(i)), i' = rev(z)), and a 2D draw needs both
// i' (for x) and dim1_reversed(i') (for y). Both are linear over GF(2) in z, so one table of
// pairs, a byte of z at a time, gives both: {rev(z), dim1_reversed(rev(z))} in the low and high
// halves (8 KiB). It replaces a 32-bit reversal and the 4 lookups above by 4 lookups.
struct UnshuffleTable {
    uint64_t t[4][256];
    constexpr UnshuffleTable() : t{} {
        for (uint32_t k = 0; k < 4; ++k)
            for (uint32_t b = 0; b < 256; ++b) {
                const uint32_t i = reverse_bits(b << (8 * k));
                t[k][b] = uint64_t(i) | uint64_t(reverse_bits(dim1_by_bits(i))) << 32;
            }
    }
};
inline constexpr UnshuffleTable kUnshuffle{};
// {rev(z), dim1_reversed(rev(z))} in the low and high halves.
constexpr uint64_t unshuffle(uint32_t z) {
    const auto& t = kUnshuffle.t;
    return t[0][z & 0xff] ^ t[1][(z >> 8) & 0xff] ^ t[2][(z >> 16) & 0xff] ^ t[3][z >> 24];
}
constexpr uint32_t dim1(uint32_t i) { return reverse_bits(dim1_reversed(i)); }

// reverse_bits of both 32-bit halves at once, each in place: one byte swap and three mask steps
// for two values (a draw's x and y), where two reverse_bits took two of each.
constexpr uint64_t reverse_bits_halves(uint64_t x) {
    x = __builtin_bswap64(x);
    x = (x >> 32) | (x << 32);  // the swap also exchanged the halves: put them back
    x = ((x >> 1) & 0x5555555555555555ull) | ((x & 0x5555555555555555ull) << 1);
    x = ((x >> 2) & 0x3333333333333333ull) | ((x & 0x3333333333333333ull) << 2);
    return ((x >> 4) & 0x0f0f0f0f0f0f0f0full) | ((x & 0x0f0f0f0f0f0f0f0full) << 4);
}

// [0, 1): the top 24 bits, so a float never rounds up to 1.
constexpr float to_unit(uint32_t x) { return float(x >> 8) * 0x1p-24f; }

}  // namespace sobol

class Sampler {
public:
    // Independent numbers from `rng` (tests that drive an integrator with a chosen stream).
    explicit Sampler(Rng rng) : type_(SamplerType::Independent), rng_(rng) {}

    static Sampler make(SamplerType type, uint64_t seed, uint64_t stream, uint64_t index) {
        return make(type, seed, stream, index, type == SamplerType::Sobol ? sobol_key(seed, stream, index) : 0);
    }
    // The sobol sampler's hash of (seed, stream, index / 2^32): the same for every sample of a
    // stream below 2^32, so a loop over one pixel's samples computes it once (make(..., key)).
    static uint64_t sobol_key(uint64_t seed, uint64_t stream, uint64_t index) {
        return hash3(seed, stream, index >> 32);
    }
    // make() with `key` = sobol_key(seed, stream, index), already computed (the independent
    // sampler ignores it).
    static Sampler make(SamplerType type, uint64_t seed, uint64_t stream, uint64_t index, uint64_t key) {
        if (type == SamplerType::Independent) return Sampler(Rng::for_sample(seed, stream, index));
        // Past 2^32 samples the Sobol' index wraps; the upper bits then go into the hash, so
        // every block of 2^32 samples is a fresh randomisation (still unbiased).
        Sampler s;
        s.type_ = SamplerType::Sobol;
        // Its PCG stream, Rng::for_sample(seed ^ 0x50b01f5eed, stream, index), serves only draws
        // past the dimension layout (rare after roulette): seeded on first use, not per sample
        // (seeding took ~110 instructions, a third of a path tracer's set-up per sample).
        s.beyond_seed_ = seed ^ 0x50b01f5eedULL;
        s.beyond_stream_ = stream;
        s.beyond_index_ = index;
        s.rng_ready_ = false;
        s.index_reversed_ = sobol::reverse_bits(uint32_t(index));
        s.key_ = key;
        return s;
    }

    SamplerType type() const { return type_; }

    // The next draw uses dimension d (a dims:: value). The independent sampler ignores it.
    void start_dimension(uint32_t d) { dim_ = d; }

    // Written out from owen() and dim0/dim1 with the reversals that cancel removed:
    //   i' = owen(i, a) = rev(LK_a(rev(i)));  x = owen(dim0(i'), b) = rev(LK_b(i'));
    //   y = owen(dim1(i'), c) = rev(LK_c(rev(dim1(i')))). sampler_test checks them against owen().
    float next_1d() {
        if (type_ == SamplerType::Independent || dim_ == dims::kBeyond) return rng().next_1d();
        const uint64_t h = mix64(key_ ^ (uint64_t(dim_) * 0x9e3779b97f4a7c15ULL));
        ++dim_;
        const uint32_t i = shuffled(uint32_t(h));
        return sobol::to_unit(sobol::reverse_bits(sobol::laine_karras(i, uint32_t(h >> 32))));
    }

    // A 1D decision this scene cannot need (one light to choose, one lobe): the sobol sampler
    // just moves past its dimension, which it would have hashed and scrambled for nothing; the
    // independent one still draws, so its stream, and every image made with it, stays as it was.
    void skip_1d() {
        if (type_ == SamplerType::Independent || dim_ == dims::kBeyond) rng().next_1d();
        else ++dim_;
    }
    // A 2D decision this sample turned out not to need: two skip_1d(), which draws from the
    // independent stream exactly what next_2d() would have.
    void skip_2d() {
        skip_1d();
        skip_1d();
    }
    // next_1d() where the decision is `needed`, else skip_1d() and 0.
    float next_1d_if(bool needed) {
        if (needed) return next_1d();
        skip_1d();
        return 0.f;
    }

    // next_2d() where the decision is `needed` (a lens sample for a camera with a finite
    // aperture), else the pair's skip and (0, 0): the same values and stream as skip_1d() twice.
    Vec2 next_2d_if(bool needed) {
        if (needed) return next_2d();
        skip_2d();
        return {0.f, 0.f};
    }

    Vec2 next_2d() {
        if (type_ == SamplerType::Independent || dim_ == dims::kBeyond) {
            Rng& r = rng();
            float a = r.next_1d();
            return {a, r.next_1d()};
        }
        const Vec2 v = sobol_2d_at(dim_);
        dim_ += 2;
        return v;
    }

    // The sobol sampler's values depend only on the dimension, not on the order of the draws:
    // an integrator may compute a draw ahead of the work it follows (sobol_2d_at) and take it
    // in its turn with next_2d(&value).
    bool order_free() const { return type_ == SamplerType::Sobol; }
    // next_2d(), where `ahead` (if not null) already holds this draw from sobol_2d_at: the stream
    // moves past it as next_2d() would.
    Vec2 next_2d(const Vec2* ahead) {
        if (!ahead) return next_2d();
        skip_2d();
        return *ahead;
    }
    // The sobol 2D draw at dimension d (a dims:: value other than kBeyond), without moving.
    Vec2 sobol_2d_at(uint32_t d) const {
        const uint64_t h = mix64(key_ ^ (uint64_t(d) * 0x9e3779b97f4a7c15ULL));
        // A third seed from the same hash by one more multiply: the scrambles only need distinct,
        // well-mixed seeds, and a full mix per coordinate showed in the render time.
        const uint32_t c = uint32_t(((h ^ (h >> 29)) * 0xbf58476d1ce4e5b9ULL) >> 32);
        // i = the shuffled index and dim1_rev(i), from the shuffle's reversed output at once.
        const uint64_t i = sobol::unshuffle(sobol::laine_karras(index_reversed_, uint32_t(h)));
        // x = rev(LK_b(i)) in the low half, y = rev(LK_c(dim1_rev(i))) in the high one.
        const uint64_t xy = sobol::reverse_bits_halves(
            uint64_t(sobol::laine_karras(uint32_t(i), uint32_t(h >> 32))) |
            uint64_t(sobol::laine_karras(uint32_t(i >> 32), c)) << 32);
        return {sobol::to_unit(uint32_t(xy)), sobol::to_unit(uint32_t(xy >> 32))};
    }

private:
    uint32_t shuffled(uint32_t seed) const {
        return uint32_t(sobol::unshuffle(sobol::laine_karras(index_reversed_, seed)));  // = owen(index, seed)
    }

    Sampler() = default;
    // The independent stream; for sobol, seeded from beyond_* on the first draw past the layout.
    Rng& rng() {
        if (!rng_ready_) {
            rng_ = Rng::for_sample(beyond_seed_, beyond_stream_, beyond_index_);
            rng_ready_ = true;
        }
        return rng_;
    }

    SamplerType type_ = SamplerType::Independent;
    uint32_t index_reversed_ = 0;  // sobol: the sample index modulo 2^32, bit-reversed
    uint32_t dim_ = 0;    // sobol: the dimension of the next draw
    uint64_t key_ = 0;    // sobol: hash of (seed, stream, index / 2^32)
    bool rng_ready_ = true;  // rng_ is seeded (always, for independent)
    uint64_t beyond_seed_ = 0, beyond_stream_ = 0, beyond_index_ = 0;  // sobol: rng_'s seed
    Rng rng_;             // independent; sobol past the dimension layout
};

}  // namespace omega
