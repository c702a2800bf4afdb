#pragma once
// Path classes for the measurement-contribution breakdown (Veach, thesis App. 8.A): a class is a
// full-path signature over L, S, D, E (pathspace/path_signature.h decides each vertex's class;
// G counts as D here, Veach's partition: a delta vertex is S, every other one D). A class is
// packed in one uint64: the length k (edges) in the top 6 bits, and bit j - 1 set when inner
// vertex j, counted from the eye (x_{k-j}), is S. Classes longer than the breakdown's maximum
// length are one key, kLongerClass, so the classes still partition path space.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "math/vec.h"
#include "pathspace/lpe.h"

namespace omega {

using PathClassKey = uint64_t;

constexpr int kMaxBreakdownLength = 16;
constexpr int kKeyLengthShift = 58;
constexpr PathClassKey kLongerClass = PathClassKey(63) << kKeyLengthShift;

inline PathClassKey path_class_key(int k, uint64_t s_bits, int max_length) {
    if (k > max_length) return kLongerClass;
    return (PathClassKey(k) << kKeyLengthShift) | (s_bits & ((uint64_t(1) << (k - 1)) - 1));
}
// k of a key; kMaxBreakdownLength + 1 for kLongerClass.
inline int path_class_length(PathClassKey key) {
    return key == kLongerClass ? kMaxBreakdownLength + 1 : int(key >> kKeyLengthShift);
}
// "L D S E" (light first), or "longer" for kLongerClass.
std::string path_class_name(PathClassKey key);
// The key of a full-path signature (light first, as strategy_signature gives it). With
// mirror_after >= 0, an S vertex (a planar-mirror connector's reflection) stands after
// signature[mirror_after].
PathClassKey path_class_key(const std::vector<VertexClass>& signature, int max_length, int mirror_after = -1);

// The same keys from the subpaths' delta flags, without building the signature: bit i - 1 of
// light_delta is light[i].delta, bit j - 1 of camera_delta is camera[j].delta (vertex 0 is the
// endpoint in both). The joined vertices of a connection are D, as in strategy_signature; with
// via_mirror, the connector's mirror (S) stands between the s light and t camera vertices.
inline PathClassKey strategy_class_key(uint64_t light_delta, uint64_t camera_delta, int s, int t, bool via_mirror,
                                       int max_length) {
    const int k = s + t - 1 + (via_mirror ? 1 : 0);
    if (k > max_length) return kLongerClass;
    // Camera vertex j is inner vertex j from the eye; the one joined (j = t - 1, s >= 1) is D.
    uint64_t bits = t >= 2 ? camera_delta & ((uint64_t(1) << (t - 1)) - 1) : 0;
    if (s >= 1 && t >= 2) bits &= ~(uint64_t(1) << (t - 2));
    if (via_mirror) bits |= uint64_t(1) << (t - 1);
    // Light vertex i is inner vertex k - i from the eye; the one joined (i = s - 1, t >= 1) is D.
    for (int i = 1; i < s; ++i)
        if (((light_delta >> (i - 1)) & 1) && !(i == s - 1 && t >= 1)) bits |= uint64_t(1) << (k - i - 1);
    return path_class_key(k, bits, max_length);
}

// Strategy t = 0: the light walk's first s vertices, all as walked, then the lens (E).
inline PathClassKey lens_class_key(uint64_t light_delta, int s, int max_length) {
    if (s > max_length) return kLongerClass;
    uint64_t bits = 0;
    for (int i = 1; i < s; ++i)
        if ((light_delta >> (i - 1)) & 1) bits |= uint64_t(1) << (s - i - 1);
    return path_class_key(s, bits, max_length);
}

// The path tracer's classes along one camera walk (eye first), fed at the same places as its
// CameraLpeTracker, so that a breakdown's classes are the light path expressions' classes.
// Concurrency: one per render thread; reset() per camera sample.
class PathClassTracker {
public:
    explicit PathClassTracker(int max_length) : max_length_(max_length) {}
    void reset() {
        s_bits_ = 0;
        contributions_.clear();
    }
    // The walk scattered at vertex k (k edges from the eye), through a delta lobe or not.
    void scatter(int k, bool delta) {
        if (delta && k < 63) s_bits_ |= uint64_t(1) << (k - 1);
        else if (k < 63) s_bits_ &= ~(uint64_t(1) << (k - 1));
    }
    // The path of k edges ends at an emitter.
    void emit(int k, const Rgb& v) { add(path_class_key(k, s_bits_, max_length_), v); }
    // Next-event estimation from vertex k (a D vertex): k + 1 edges.
    void emit_via(int k, const Rgb& v) { add(path_class_key(k + 1, s_bits_ & low(k - 1), max_length_), v); }
    // The planar-mirror connector from vertex k: vertex k is D, the mirror (vertex k + 1) is S.
    void emit_via_mirror(int k, const Rgb& v) {
        add(path_class_key(k + 2, (s_bits_ & low(k - 1)) | (k < 63 ? uint64_t(1) << k : 0), max_length_), v);
    }
    const std::vector<std::pair<PathClassKey, Rgb>>& contributions() const { return contributions_; }

private:
    static uint64_t low(int n) { return n >= 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1; }
    void add(PathClassKey key, const Rgb& v) {
        if (!is_black(v)) contributions_.emplace_back(key, v);
    }
    int max_length_;
    uint64_t s_bits_ = 0;
    std::vector<std::pair<PathClassKey, Rgb>> contributions_;
};

}  // namespace omega
