// Scene::intersect_packet and occluded_packet against intersect() and occluded(), bit for bit: a
// tracer may batch its rays only if no image changes (any thread count, resume, merged parts).
#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <string>
#include <vector>

#include "math/frame.h"
#include "sampling/rng.h"
#include "sampling/warp.h"
#include "scene/scene.h"
#include "scene/scene_parser.h"
#include "scene/spawn.h"
#include "shared_data.h"

namespace omega {
namespace {

// Triangles, a sphere inside a masked (stochastic) quad, a textured sphere seen through it.
const char* kMixed = R"(omega: 1
sensor: {type: perspective, fov: 60, to_world: {look_at: {origin: [0, 0, 4], target: [0, 0, 0], up: [0, 1, 0]}},
         film: {width: 32, height: 32}}
lights: [{type: constant, radiance: 1}]
materials:
  m: {type: diffuse, reflectance: 0.5}
  half: {type: diffuse, reflectance: 0.5, opacity: 0.5}
shapes:
  - {type: cube, material: m, flip_normals: true, to_world: {scale: [3, 3, 3]}}
  - {type: sphere, material: m, center: [0.5, 0, 0], radius: 0.6}
  - {type: sphere, material: m, center: [-1, 1, -1], radius: 0.4, flip_normals: true}
  - {type: rectangle, material: half, to_world: [{scale: [1.5, 1.5, 1]}, {translate: [0, 0, 1]}]}
)";

bool same_bits(float a, float b) { return std::bit_cast<uint32_t>(a) == std::bit_cast<uint32_t>(b); }
bool same_bits(const Vec3& a, const Vec3& b) { return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.z, b.z); }
bool same_hit(const SurfaceHit& a, const SurfaceHit& b) {
    return same_bits(a.p, b.p) && same_bits(a.t, b.t) && same_bits(a.p_error, b.p_error) && a.shape == b.shape &&
           same_bits(a.ng, b.ng) && a.prim == b.prim && same_bits(a.ns, b.ns) && a.planar == b.planar &&
           same_bits(a.uv.x, b.uv.x) && same_bits(a.uv.y, b.uv.y);
}

// The rays a tracer issues: camera rays, incoherent rays from inside the scene box, bounces
// spawned from their hits, rays that start exactly on the surface they leave (the self-hit
// retry and filter), and shadow rays between hit points (some blocked, some not).
std::vector<Ray> tracer_rays(const Scene& scene, int n) {
    Rng rng(5, 0);
    const SceneBounds& b = scene.bounds();
    const Vec3 lo = b.lo + (b.hi - b.lo) * 0.05f, ext = (b.hi - b.lo) * 0.9f;
    const Sensor& sensor = scene.sensor();
    std::vector<Ray> rays;
    SurfaceHit prev;
    bool have_prev = false;
    while (int(rays.size()) < n) {
        rays.push_back(sensor.generate_ray({rng.next_1d() * float(sensor.width), rng.next_1d() * float(sensor.height)},
                                           {0.5f, 0.5f}));
        Ray r;
        r.o = lo + ext * Vec3(rng.next_1d(), rng.next_1d(), rng.next_1d());
        r.d = square_to_uniform_sphere({rng.next_1d(), rng.next_1d()});
        rays.push_back(r);
        SurfaceHit h;
        if (!scene.intersect(r, h)) continue;
        const Vec3 n_out = dot(h.ng, r.d) < 0 ? h.ng : -h.ng;
        const Vec3 w = Frame::from_normal(n_out).to_world(square_to_cosine_hemisphere({rng.next_1d(), rng.next_1d()}));
        rays.push_back(spawn_ray(h, w));
        Ray on = spawn_ray(h, w);
        on.o = h.p;  // no offset: the first hit is often the surface itself
        if (h.planar) rays.push_back(on);
        if (have_prev) rays.push_back(spawn_ray_to(h, prev.p, prev.p_error, prev.ng));
        prev = h;
        have_prev = true;
    }
    return rays;
}

struct Tally {
    int found = 0, missed = 0, blocked = 0, clear = 0, spheres = 0;
};

// Packets of every size from 1 to kPacket, so partial packets (idle lanes) are checked too.
Tally check_packets(const Scene& scene, const std::vector<Ray>& rays) {
    Tally tally;
    size_t at = 0;
    for (size_t size = 1; at < rays.size(); size = size % Scene::kPacket + 1) {
        const size_t n = std::min(size, rays.size() - at);
        const std::span<const Ray> packet(rays.data() + at, n);
        SurfaceHit hits[Scene::kPacket];
        bool found[Scene::kPacket], blocked[Scene::kPacket];
        scene.intersect_packet(packet, hits, found);
        scene.occluded_packet(packet, blocked);
        for (size_t i = 0; i < n; ++i) {
            SurfaceHit h;
            const bool f = scene.intersect(packet[i], h);
            EXPECT_EQ(found[i], f) << "ray " << at + i;
            if (f && found[i]) {
                EXPECT_TRUE(same_hit(hits[i], h)) << "ray " << at + i << ": t " << hits[i].t << " vs " << h.t;
                tally.spheres += !h.planar;
            }
            EXPECT_EQ(blocked[i], scene.occluded(packet[i])) << "ray " << at + i;
            (f ? tally.found : tally.missed) += 1;
            (blocked[i] ? tally.blocked : tally.clear) += 1;
        }
        at += n;
    }
    return tally;
}

TEST(PacketQuery, CornellBoxEqualsSingleRaysBitForBit) {
    auto scene = Scene::build(parse_scene_file(test::source_dir() + "/scenes/cornell-box.yaml"));
    const Tally t = check_packets(*scene, tracer_rays(*scene, 40000));
    EXPECT_GT(t.found, 20000);
    EXPECT_GT(t.missed, 100);  // camera rays through the open side, rays from outside the box
    EXPECT_GT(t.blocked, 1000);
    EXPECT_GT(t.clear, 1000);
}

TEST(PacketQuery, SpheresMasksAndSelfHitsEqualSingleRaysBitForBit) {
    auto scene = Scene::build(parse_scene_string(kMixed, test::source_dir() + "/packet.yaml"));
    ASSERT_TRUE(scene->shapes()[3].masked());
    const Tally t = check_packets(*scene, tracer_rays(*scene, 40000));
    EXPECT_GT(t.spheres, 1000);
    EXPECT_GT(t.blocked, 1000);
    EXPECT_GT(t.clear, 1000);
}

TEST(PacketQuery, VeachMisEqualsSingleRaysBitForBit) {
    auto scene = Scene::build(parse_scene_file(test::source_dir() + "/scenes/veach-mis.yaml"));
    const Tally t = check_packets(*scene, tracer_rays(*scene, 20000));
    EXPECT_GT(t.found, 10000);
    EXPECT_GT(t.spheres, 50);
}

TEST(PacketQuery, RejectsMoreThanAPacket) {
    auto scene = Scene::build(parse_scene_string(kMixed, test::source_dir() + "/packet.yaml"));
    std::vector<Ray> rays(Scene::kPacket + 1);
    SurfaceHit hits[Scene::kPacket + 1];
    bool flags[Scene::kPacket + 1];
    EXPECT_THROW(scene->intersect_packet(rays, hits, flags), std::logic_error);
    EXPECT_THROW(scene->occluded_packet(rays, flags), std::logic_error);
}

}  // namespace
}  // namespace omega
