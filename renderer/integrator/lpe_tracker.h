#pragma once
// The path tracer's light path expression state along one camera walk. The walk builds the path
// eye to light, so it runs the reversed automata: E first, then every vertex it scatters at, and
// L where a contribution ends the path (an emitter hit, or next-event estimation through one
// more vertex). A contribution is added to every AOV whose automaton accepts after that L: the
// same value the beauty image gets, so AOVs that partition path space sum to the beauty.
// All AOVs step together through LpeSet's product automaton (one lookup per vertex); a set whose
// product is too large steps each AOV's automaton instead.
//
// Concurrency: one per render thread (a local of the tile loop); reset() per camera sample.
#include <array>
#include <bit>

#include "math/vec.h"
#include "pathspace/lpe.h"
#include "pathspace/path_signature.h"

namespace omega {

class CameraLpeTracker {
public:
    // The AOVs must outlive the tracker.
    explicit CameraLpeTracker(const LpeSet& set)
        : n_(set.size()), product_(set.has_products() ? &set.reverse_product() : nullptr), glossy_(set.uses_glossy()) {
        if (product_) start_product_ = product_->step(product_->start, VertexClass::E);
        for (size_t i = 0; i < n_; ++i) {
            const LpeDfa& d = set[i].reverse;
            next_[i] = d.next.data();
            accept_[i] = d.accept.data();
            start_[i] = d.step(d.start, VertexClass::E);
        }
    }

    // A new camera sample: every value zero, every automaton past E.
    void reset() {
        for (size_t i = 0; i < n_; ++i) value_[i] = Rgb(0.f);
        if (product_) state_product_ = start_product_;
        else
            for (size_t i = 0; i < n_; ++i) state_[i] = start_[i];
    }
    // The walk continued through a vertex with this BSDF, through a delta lobe or not.
    void scatter(const Bsdf& bsdf, bool delta) { step_all(delta ? VertexClass::S : nondelta(bsdf)); }
    // The path ends at an emitter here: contribution v (already weighted) for x_0 = L.
    void emit(const Rgb& v) {
        if (product_) return add(product_->accept_l[state_product_], v);
        for (size_t i = 0; i < n_; ++i)
            if (accept_[i][step(i, state_[i], VertexClass::L)]) value_[i] += v;
    }
    // Next-event estimation: the path goes through one more (non-delta) scattering at this
    // BSDF, then ends at L.
    void emit_via(const Bsdf& bsdf, const Rgb& v) {
        const VertexClass c = nondelta(bsdf);
        if (product_) return add(product_->accept_l[product_->step(state_product_, c)], v);
        for (size_t i = 0; i < n_; ++i)
            if (accept_[i][step(i, step(i, state_[i], c), VertexClass::L)]) value_[i] += v;
    }
    // The planar-mirror connector: one more non-delta scattering at this BSDF, a delta
    // reflection (S) at the mirror, then L.
    void emit_via_mirror(const Bsdf& bsdf, const Rgb& v) {
        const VertexClass c = nondelta(bsdf);
        if (product_) return add(product_->accept_l[product_->step(product_->step(state_product_, c), VertexClass::S)], v);
        for (size_t i = 0; i < n_; ++i)
            if (accept_[i][step(i, step(i, step(i, state_[i], c), VertexClass::S), VertexClass::L)]) value_[i] += v;
    }
    size_t size() const { return n_; }
    const Rgb& value(size_t i) const { return value_[i]; }

private:
    VertexClass nondelta(const Bsdf& bsdf) const { return glossy_ ? nondelta_class(bsdf) : VertexClass::D; }
    uint8_t step(size_t i, uint8_t state, VertexClass c) const { return next_[i][state][size_t(c)]; }
    void step_all(VertexClass c) {
        if (product_) state_product_ = product_->step(state_product_, c);
        else
            for (size_t i = 0; i < n_; ++i) state_[i] = step(i, state_[i], c);
    }
    void add(uint32_t mask, const Rgb& v) {
        for (; mask; mask &= mask - 1) value_[size_t(std::countr_zero(mask))] += v;
    }

    size_t n_;
    const LpeProduct* product_;
    bool glossy_;  // some expression tells G from D
    uint16_t start_product_ = 0, state_product_ = 0;
    // Each AOV's reversed automaton, by pointer: no indirection through the set per step.
    std::array<const std::array<uint8_t, kVertexClasses>*, kMaxAovs> next_{};
    std::array<const uint8_t*, kMaxAovs> accept_{};
    std::array<uint8_t, kMaxAovs> start_{};
    std::array<uint8_t, kMaxAovs> state_{};
    std::array<Rgb, kMaxAovs> value_{};
};

}  // namespace omega
