#pragma once
// The path tracer's light path expression state along one camera walk. The walk builds the path
// eye to light, so it runs each expression's reversed automaton: E first, then every vertex it
// scatters at, and L where a contribution ends the path (an emitter hit, or next-event
// estimation through one more vertex). A contribution is added to every AOV whose automaton
// accepts after that L: the same value the beauty image gets, so AOVs that partition path space
// sum to the beauty.
//
// Concurrency: one per render thread (a local of the tile loop); reset() per camera sample.
#include <array>

#include "math/vec.h"
#include "pathspace/lpe.h"

namespace omega {

class CameraLpeTracker {
public:
    // The AOVs must outlive the tracker's use.
    explicit CameraLpeTracker(const LpeSet& set) : set_(set), n_(set.size()) {}

    // A new camera sample: every value zero, every automaton past E.
    void reset() {
        for (size_t i = 0; i < n_; ++i) {
            const LpeDfa& d = set_[i].reverse;
            state_[i] = d.step(d.start, VertexClass::E);
            value_[i] = Rgb(0.f);
        }
    }
    // The walk continued through a vertex of class c.
    void scatter(VertexClass c) {
        for (size_t i = 0; i < n_; ++i) state_[i] = set_[i].reverse.step(state_[i], c);
    }
    // The path ends at an emitter here: contribution v (already weighted) for x_0 = L.
    void emit(const Rgb& v) {
        for (size_t i = 0; i < n_; ++i) {
            const LpeDfa& d = set_[i].reverse;
            if (d.accepts(d.step(state_[i], VertexClass::L))) value_[i] += v;
        }
    }
    // Next-event estimation: the path goes through one more vertex of class c, then ends at L.
    void emit_via(VertexClass c, const Rgb& v) {
        for (size_t i = 0; i < n_; ++i) {
            const LpeDfa& d = set_[i].reverse;
            if (d.accepts(d.step(d.step(state_[i], c), VertexClass::L))) value_[i] += v;
        }
    }
    size_t size() const { return n_; }
    const Rgb& value(size_t i) const { return value_[i]; }

private:
    const LpeSet& set_;
    size_t n_;
    std::array<uint8_t, kMaxAovs> state_{};
    std::array<Rgb, kMaxAovs> value_{};
};

}  // namespace omega
