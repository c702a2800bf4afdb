#pragma once
// A sum of doubles that does not depend on the order of its terms: each term is added exactly
// into a fixed-point accumulator (Kulisch's long accumulator, cut down to the range a render
// needs), so two sums that saw the same terms in any order, on any threads, in any grouping
// (passes, resumed renders, sample ranges), hold the same bits. The path-class breakdown needs
// this: its statistics are summed per thread, and the project's rule is that the same scene,
// spp and seed give the same output bit for bit whatever the thread count.
//
// Range: terms are exact down to 2^kMinExp; bits below that are dropped (the same bits whatever
// the order). |term| >= 2^kMaxExp, or a non-finite term, marks the sum overflowed (value() NaN).
//
// Concurrency: a plain value; one thread at a time.
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>

namespace omega {

class ExactSum {
public:
    static constexpr int kMinExp = -320;
    static constexpr int kMaxExp = 320;
    static constexpr int kLimbBits = 32;
    static constexpr int kLimbs = (kMaxExp - kMinExp) / kLimbBits + 3;  // + room for carries

    void add(double x) {
        // Straight from the bits (frexp and ldexp are library calls): x = M 2^(E - 1075).
        const uint64_t bits = std::bit_cast<uint64_t>(x);
        const int biased = int((bits >> 52) & 0x7ff);
        uint64_t m53 = bits & ((uint64_t(1) << 52) - 1);
        if (biased == 0x7ff || biased - 1022 >= kMaxExp) {  // inf, nan, or |x| >= 2^kMaxExp
            overflow_ = true;
            return;
        }
        if (biased != 0) m53 |= uint64_t(1) << 52;
        if (m53 == 0) return;
        int p = (biased == 0 ? -1074 : biased - 1075) - kMinExp;  // bit position of M's lowest bit
        if (p < 0) {
            if (p <= -53) return;
            m53 >>= -p;  // drops the bits below 2^kMinExp: the same whatever the order
            p = 0;
        }
        const bool neg = bits >> 63;
        const int sh = p % kLimbBits;
        // M 2^sh spans up to 84 bits: three 32-bit digits.
        const uint64_t d[3] = {(m53 << sh) & 0xffffffffu, (m53 >> (kLimbBits - sh)) & 0xffffffffu,
                               sh == 0 ? 0 : m53 >> (2 * kLimbBits - sh)};
        const size_t i0 = size_t(p / kLimbBits);
        for (size_t j = 0; j < 3; ++j) limbs_[i0 + j] += neg ? -int64_t(d[j]) : int64_t(d[j]);
        if (++pending_ >= kNormalizeEvery) normalize();
    }

    void add(const ExactSum& o) {
        overflow_ = overflow_ || o.overflow_;
        for (size_t i = 0; i < limbs_.size(); ++i) limbs_[i] += o.limbs_[i];
        pending_ += o.pending_ + 1;
        if (pending_ >= kNormalizeEvery) normalize();
    }

    // The sum rounded to double (from the normalised digits, so it depends only on the terms).
    double value() const {
        if (overflow_) return std::numeric_limits<double>::quiet_NaN();
        ExactSum n = *this;
        n.normalize();
        double r = 0;
        for (int i = kLimbs - 1; i >= 0; --i) r += std::ldexp(double(n.limbs_[size_t(i)]), i * kLimbBits + kMinExp);
        return r;
    }

    // The digits, normalised: every limb but the last in [0, 2^32) (for comparison and text).
    std::array<int64_t, kLimbs> digits() const {
        ExactSum n = *this;
        n.normalize();
        return n.limbs_;
    }
    bool overflowed() const { return overflow_; }
    // Text that set_text() reads back to the same digits: "nan" (overflowed), or "I:d,d,..."
    // with the hex digits of limbs I, I+1, ... (the last may be negative); "0" for zero.
    std::string text() const;
    // Throws std::invalid_argument for text that text() would not write.
    void set_text(std::string_view t);
    void set_digits(const std::array<int64_t, kLimbs>& d, bool overflow) {
        limbs_ = d;
        overflow_ = overflow;
        pending_ = 0;
    }

private:
    // Each add moves at most 2^32 into a limb: carry well before an int64 could overflow.
    static constexpr int kNormalizeEvery = 1 << 24;
    void normalize() {
        for (int i = 0; i + 1 < kLimbs; ++i) {
            const int64_t carry = limbs_[size_t(i)] >> kLimbBits;  // floor division by 2^32
            limbs_[size_t(i)] -= carry * (int64_t(1) << kLimbBits);
            limbs_[size_t(i + 1)] += carry;
        }
        pending_ = 0;
    }
    std::array<int64_t, kLimbs> limbs_{};
    int pending_ = 0;
    bool overflow_ = false;
};

}  // namespace omega
