#include "scene/spawn.h"

#include <gtest/gtest.h>

#include <limits>

#include "sampling/rng.h"

namespace omega {
namespace {

uint32_t bits(float v) { return std::bit_cast<uint32_t>(v); }

// The ray origin as the scalar code computed it before the four-lane form: the reference every
// spawned ray must keep, bit for bit (images and exact resume depend on it).
Vec3 scalar_offset_ray_origin(const Vec3& p, const Vec3& p_error, const Vec3& n, const Vec3& w) {
    float d = dot(abs(n), p_error);
    Vec3 offset = n * d;
    if (dot(w, n) < 0) offset = -offset;
    const Vec3 po = p + offset;
    return {next_float_toward(po.x, offset.x), next_float_toward(po.y, offset.y), next_float_toward(po.z, offset.z)};
}

float signed_pow(Rng& rng, float lo, float hi) {
    const float v = std::exp2(lo + (hi - lo) * rng.next_1d());
    return rng.next_1d() < 0.5f ? -v : v;
}

TEST(Spawn, OffsetRayOriginEqualsTheScalarFormBitForBit) {
    Rng rng(11, 0);
    const float inf = std::numeric_limits<float>::infinity();
    // Axis-aligned normals (the zero components are the selects' edge), zero error, huge and
    // tiny coordinates, and points on the axes.
    const Vec3 normals[] = {{0, 0, 1}, {0, -1, 0}, {-1, 0, 0}, {0.f, -0.f, 1.f}};
    long long n_checked = 0;
    for (int i = 0; i < 200000; ++i) {
        Vec3 p(signed_pow(rng, -20, 20), signed_pow(rng, -20, 20), signed_pow(rng, -20, 20));
        if (i % 7 == 0) p.y = 0.f;
        if (i % 11 == 0) p.x = -0.f;
        if (i % 13 == 0) p.z = inf;
        Vec3 err = abs(p) * gamma_bound(int(1 + i % 7));
        if (i % 5 == 0) err = Vec3(0.f);
        Vec3 n = i % 3 == 0 ? normals[i % 4] : normalize(Vec3(signed_pow(rng, -8, 0), signed_pow(rng, -8, 0), signed_pow(rng, -8, 0)));
        Vec3 w = normalize(Vec3(rng.next_1d() - 0.5f, rng.next_1d() - 0.5f, rng.next_1d() - 0.5f));
        if (i % 17 == 0) w = Vec3(0.f);
        const Vec3 a = offset_ray_origin(p, err, n, w), b = scalar_offset_ray_origin(p, err, n, w);
        ASSERT_EQ(bits(a.x), bits(b.x)) << i;
        ASSERT_EQ(bits(a.y), bits(b.y)) << i;
        ASSERT_EQ(bits(a.z), bits(b.z)) << i;
        ++n_checked;
    }
    EXPECT_EQ(n_checked, 200000);
}

// The offset is what keeps a spawned ray off its own surface: the origin lies strictly on the
// side the direction leaves to, by at least the error bound along the normal.
TEST(Spawn, OffsetOriginLeavesTheSurfaceOnTheDirectionsSide) {
    Rng rng(12, 0);
    for (int i = 0; i < 20000; ++i) {
        const Vec3 p(signed_pow(rng, -4, 12), signed_pow(rng, -4, 12), 0.f);
        const Vec3 err = abs(p) * gamma_bound(4) + Vec3(1e-6f);
        const Vec3 w = normalize(Vec3(rng.next_1d() - 0.5f, rng.next_1d() - 0.5f, rng.next_1d() - 0.5f));
        const Vec3 o = offset_ray_origin(p, err, {0, 0, 1}, w);
        if (w.z > 0) {
            ASSERT_GT(o.z, err.z) << i;
        } else if (w.z < 0) {
            ASSERT_LT(o.z, -err.z) << i;
        }
    }
}

}  // namespace
}  // namespace omega
