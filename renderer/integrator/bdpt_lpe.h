#pragma once
// BDPT's light path expression matching. Every (s, t) strategy of one sample joins a prefix of
// the same light subpath to a prefix of the same camera subpath, so each subpath is run through
// each AOV's automaton once per sample (the light subpath forwards, the camera subpath through
// the reversed automaton), and a connection is then decided by Lpe::join on the two states,
// after stepping over the joined vertices: a few table lookups, whatever the path's length.
// All AOVs go together through LpeSet's product automata when it has them.
// The vertex classes are those of pathspace/path_signature.h (strategy_signature gives the same
// matches by reading the whole path; a test checks that they agree).
//
// Concurrency: one per render thread (in BdptScratch); prepare() once per sample, then match*().
#include <array>
#include <cstdint>
#include <vector>

#include "pathspace/lpe.h"
#include "pathspace/vertex.h"

namespace omega {

class BdptLpeMatcher {
public:
    // The subpaths of this sample (vectors as BdptTracer holds them; n_* of their vertices are
    // used). Keeps pointers to neither.
    void prepare(const LpeSet& set, const std::vector<PathVertex>& light, int n_light,
                 const std::vector<PathVertex>& camera, int n_camera);
    // Bit i: AOV i matches strategy (s, t >= 1)'s full path; with via_mirror, the planar-mirror
    // connector's (pathspace/mirror_connector.h): a delta reflection (S) between the two sides.
    // Inline for the product automata (the usual case): it runs once per connection.
    uint32_t match(int s, int t, bool via_mirror = false) const {
        if (!product_) return match_each(s, t, via_mirror);
        const LpeProduct& fp = set_->forward_product();
        const LpeProduct& rp = set_->reverse_product();
        uint16_t f = s == 0 ? fp.start : s == 1 ? p_after_l_ : fp.step(pfwd_[size_t(s - 2)], light_joined_[size_t(s - 1)]);
        if (via_mirror) f = fp.step(f, VertexClass::S);
        const uint16_t r =
            t == 1 ? p_after_e_ : rp.step(prev_[size_t(t - 2)], s == 0 ? VertexClass::L : camera_joined_[size_t(t - 1)]);
        return set_->join(f, r);
    }
    // Strategy t = 0: the light walk's first s vertices, then the lens.
    uint32_t match_lens(int s) const;

private:
    uint32_t match_each(int s, int t, bool via_mirror) const;  // each AOV's own automaton

    const LpeSet* set_ = nullptr;
    size_t n_ = 0;  // AOVs
    int n_light_ = 0, n_camera_ = 0;
    // Per vertex: its class inside a walk and as a joined (connection) vertex.
    std::vector<VertexClass> light_walk_, light_joined_, camera_walk_, camera_joined_;
    // fwd_[a * n_light + i]: AOV a's forward state after light[0..i] as walked (light[0] = L).
    // rev_[a * n_camera + j]: its reverse state after camera[0..j] as walked (camera[0] = E).
    std::vector<uint8_t> fwd_, rev_;
    std::array<uint8_t, kMaxAovs> after_l_{}, after_e_{};  // forward after L; reverse after E
    // With LpeSet's product automata (the usual case): the same, one state for all AOVs.
    bool product_ = false;
    std::vector<uint16_t> pfwd_, prev_;
    uint16_t p_after_l_ = 0, p_after_e_ = 0;
};

}  // namespace omega
