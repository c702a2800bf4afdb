#include "integrator/bdpt_lpe.h"

#include "pathspace/path_signature.h"

namespace omega {

void BdptLpeMatcher::prepare(const LpeSet& set, const std::vector<PathVertex>& light, int n_light,
                             const std::vector<PathVertex>& camera, int n_camera) {
    set_ = &set;
    n_ = set.size();
    n_light_ = n_light;
    n_camera_ = n_camera;
    // Grown, never shrunk: only the first n_light / n_camera entries are read, and this runs per
    // sample (six resizes were a third of its cost).
    auto fit = [](auto& v, int n) {
        if (v.size() < size_t(n)) v.resize(size_t(n));
    };
    fit(light_walk_, n_light);
    fit(light_joined_, n_light);
    fit(camera_walk_, n_camera);
    fit(camera_joined_, n_camera);
    // One BSDF query per vertex: its non-delta class serves as joined and, unless the walk took
    // a delta lobe there, as walked.
    // Without G in any expression, D and G behave alike: no BSDF query at all.
    const bool glossy = set.uses_glossy();
    auto classify = [glossy](const PathVertex& v, VertexClass& walk, VertexClass& joined) {
        joined = glossy && v.bsdf ? nondelta_class(*v.bsdf) : VertexClass::D;
        walk = v.delta ? VertexClass::S : joined;
    };
    if (n_light > 0) light_walk_[0] = light_joined_[0] = VertexClass::L;
    for (int i = 1; i < n_light; ++i) classify(light[size_t(i)], light_walk_[size_t(i)], light_joined_[size_t(i)]);
    if (n_camera > 0) camera_walk_[0] = camera_joined_[0] = VertexClass::E;
    for (int j = 1; j < n_camera; ++j) classify(camera[size_t(j)], camera_walk_[size_t(j)], camera_joined_[size_t(j)]);
    // Raw pointers: stores through uint8_t alias everything, so members would be reloaded per step.
    const VertexClass* lw = light_walk_.data();
    const VertexClass* cw = camera_walk_.data();
    product_ = set.has_products();
    if (product_) {
        const LpeProduct& fp = set.forward_product();
        const LpeProduct& rp = set.reverse_product();
        p_after_l_ = fp.step(fp.start, VertexClass::L);
        p_after_e_ = rp.step(rp.start, VertexClass::E);
        fit(pfwd_, n_light);
        fit(prev_, n_camera);
        uint16_t q = fp.start;
        for (int i = 0; i < n_light; ++i) pfwd_[size_t(i)] = q = fp.step(q, lw[i]);
        q = rp.start;
        for (int j = 0; j < n_camera; ++j) prev_[size_t(j)] = q = rp.step(q, cw[j]);
        return;
    }
    fit(fwd_, int(n_) * n_light);
    fit(rev_, int(n_) * n_camera);
    for (size_t a = 0; a < n_; ++a) {
        const Lpe& e = set[a];
        after_l_[a] = e.forward.step(e.forward.start, VertexClass::L);
        after_e_[a] = e.reverse.step(e.reverse.start, VertexClass::E);
        const std::array<uint8_t, kVertexClasses>* fnext = e.forward.next.data();
        const std::array<uint8_t, kVertexClasses>* rnext = e.reverse.next.data();
        uint8_t* fwd = fwd_.data() + a * size_t(n_light);
        uint8_t* rev = rev_.data() + a * size_t(n_camera);
        uint8_t q = e.forward.start;
        for (int i = 0; i < n_light; ++i) fwd[i] = q = fnext[q][size_t(lw[i])];
        q = e.reverse.start;
        for (int j = 0; j < n_camera; ++j) rev[j] = q = rnext[q][size_t(cw[j])];
    }
}

uint32_t BdptLpeMatcher::match_each(int s, int t, bool via_mirror) const {
    uint32_t mask = 0;
    for (size_t a = 0; a < n_; ++a) {
        const Lpe& e = (*set_)[a];
        // The light side, its last vertex joined (s >= 2); s = 1 is a fresh light sample.
        uint8_t f;
        if (s == 0) f = e.forward.start;
        else if (s == 1) f = after_l_[a];
        else f = e.forward.step(fwd_[a * size_t(n_light_) + size_t(s - 2)], light_joined_[size_t(s - 1)]);
        if (via_mirror) f = e.forward.step(f, VertexClass::S);
        // The camera side, read eye first; with s = 0 its last vertex is the emitter it hit.
        uint8_t r;
        if (t == 1) r = after_e_[a];
        else {
            const uint8_t before = rev_[a * size_t(n_camera_) + size_t(t - 2)];
            r = e.reverse.step(before, s == 0 ? VertexClass::L : camera_joined_[size_t(t - 1)]);
        }
        if (f && r && e.join(f, r)) mask |= 1u << a;
    }
    return mask;
}

uint32_t BdptLpeMatcher::match_lens(int s) const {
    if (product_) return set_->join(pfwd_[size_t(s - 1)], p_after_e_);
    uint32_t mask = 0;
    for (size_t a = 0; a < n_; ++a) {
        const Lpe& e = (*set_)[a];
        const uint8_t f = fwd_[a * size_t(n_light_) + size_t(s - 1)];
        if (f && e.join(f, after_e_[a])) mask |= 1u << a;
    }
    return mask;
}

}  // namespace omega
