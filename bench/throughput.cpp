// bench/throughput [SCENE] [SPP] [N] [REPEATS] [SIZE]: renders a scene (default: the Cornell box)
// at SIZE x SIZE (default 256) with max_depth 9 and prints samples/s and rays/s for 1, 2, 4, ... N
// threads (N: every hardware thread), with the speedup over 1 thread next to Embree's own, and each
// rate against Embree's raw rate for incoherent rays on the same BVH at the same thread count, all
// in the same run, and the rate of a bare one-ray-at-a-time loop on the same BVH (the ceiling of
// that design), with what batching 8 paths' rays into Embree packets would gain on that loop and on
// raw rays. Last, for each integrator, the speedup on 2 to 16 threads that its schedule alone
// allows (barriers, imbalance, serial parts; integrator/schedule_probe.h), recorded on one thread,
// next to the speedup measured here: the figure issue 12 asks for on machines this one cannot show.
// Every figure is the median of REPEATS (default 3) measurements, each renderer run alternating
// with an Embree run; a ratio is the median of those pairs' ratios, with their range beside it, so
// one disturbed run on a shared machine neither moves the figure nor goes unseen.
#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "integrator/render_session.h"
#include "sampling/rng.h"
#include "math/frame.h"
#include "sampling/warp.h"
#include "scene/scene.h"
#include "scene/scene_parser.h"

using namespace omega;

namespace {

struct Rate {
    double samples_per_s, rays_per_s, seconds;
};

// With a probe (one thread only), the render also records its schedule (integrator/schedule_probe.h).
Rate render_rate(const Scene& scene, int threads, long long spp, ScheduleProbe* probe = nullptr) {
    RenderSettings rs;
    rs.threads = threads;
    rs.halt.spp = spp;
    rs.integrator = scene.desc().integrator;
    RenderSession session(scene, rs);
    if (probe) {
        session.set_schedule_probe(probe);
        probe->start();
    }
    PassReport r = session.run();
    if (probe) probe->stop();
    return {r.samples_per_s, r.rays_per_s, r.elapsed_s};
}

// An Embree ray from o along d over [0, tfar), as the renderer fills one (scene.cpp).
RTCRay embree_ray(const Vec3& o, const Vec3& d, float tfar) {
    RTCRay r;
    r.org_x = o.x; r.org_y = o.y; r.org_z = o.z;
    r.dir_x = d.x; r.dir_y = d.y; r.dir_z = d.z;
    r.tnear = 0; r.tfar = tfar; r.mask = ~0u; r.flags = 0; r.time = 0; r.id = 0;
    return r;
}

// Incoherent closest-hit queries: origins uniform in the scene box, directions uniform on the
// sphere, one rtcIntersect1 each (the same query the renderer issues); with `packets`, the same
// rays eight at a time through rtcIntersect8 (what Scene::intersect_packet issues).
double embree_raw_rate(const Scene& scene, int threads, long long rays, bool packets = false) {
    RTCScene rtc = scene.embree_scene();
    const SceneBounds& b = scene.bounds();
    Vec3 lo = b.lo + (b.hi - b.lo) * 0.05f, ext = (b.hi - b.lo) * 0.9f;
    tbb::task_arena arena(threads);
    std::atomic<uint64_t> hits{0};
    auto t0 = std::chrono::steady_clock::now();
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<long long>(0, rays, 4096), [&](const tbb::blocked_range<long long>& r) {
            uint64_t local_hits = 0;
            RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            const auto ray_at = [&](long long i) {
                Rng rng = Rng::for_sample(7, 0, uint64_t(i));
                Vec3 o = lo + ext * Vec3(rng.next_1d(), rng.next_1d(), rng.next_1d());
                return std::pair{o, square_to_uniform_sphere({rng.next_1d(), rng.next_1d()})};
            };
            for (long long i = r.begin(); packets && i < r.end(); i += 8) {
                alignas(32) int valid[8];
                alignas(32) RTCRayHit8 rh;
                for (int k = 0; k < 8; ++k) {
                    valid[k] = i + k < r.end() ? -1 : 0;
                    if (!valid[k]) continue;
                    const auto [o, d] = ray_at(i + k);
                    rh.ray.org_x[k] = o.x; rh.ray.org_y[k] = o.y; rh.ray.org_z[k] = o.z;
                    rh.ray.dir_x[k] = d.x; rh.ray.dir_y[k] = d.y; rh.ray.dir_z[k] = d.z;
                    rh.ray.tnear[k] = 0; rh.ray.tfar[k] = kInfinity; rh.ray.mask[k] = ~0u;
                    rh.ray.flags[k] = 0; rh.ray.time[k] = 0; rh.ray.id[k] = unsigned(k);
                    rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
                }
                rtcIntersect8(valid, rtc, &ctx, &rh);
                for (int k = 0; k < 8; ++k) local_hits += valid[k] && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
            }
            for (long long i = r.begin(); !packets && i != r.end(); ++i) {
                const auto [o, d] = ray_at(i);
                RTCRayHit rh;
                rh.ray = embree_ray(o, d, kInfinity);
                rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                rtcIntersect1(rtc, &ctx, &rh);
                local_hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            }
            hits += local_hits;
        });
    });
    double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return double(rays) / s;
}

// What both bare loops share: the BVH, the camera, the shadow rays' target and the hit offset.
struct BareScene {
    RTCScene rtc;
    const Sensor& sensor;
    int w, h;
    Vec3 target;
    float eps;
    explicit BareScene(const Scene& s)
        : rtc(s.embree_scene()), sensor(s.sensor()), w(s.sensor().width), h(s.sensor().height),
          target((s.bounds().lo + s.bounds().hi) * 0.5f), eps(1e-4f * max_component(s.bounds().hi - s.bounds().lo)) {}
};

// Rays/s of a bare loop on `threads` threads: rows(scene, ctx, y0, y1) traces the image rows
// [y0, y1) and returns how many rays it traced.
template <class Rows>
double bare_rate(const Scene& scene, int threads, Rows&& rows) {
    const BareScene bs(scene);
    tbb::task_arena arena(threads);
    std::atomic<uint64_t> rays{0};
    auto t0 = std::chrono::steady_clock::now();
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, bs.h), [&](const tbb::blocked_range<int>& r) {
            RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            rays += rows(bs, ctx, r.begin(), r.end());
        });
    });
    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return double(rays.load()) / secs;
}

// The ceiling of a tracer that issues one ray at a time: the same camera rays and, per bounce,
// one closest hit, one shadow ray (to the scene box's centre) and a cosine-distributed bounce,
// to max_depth 9 without roulette, with no materials, lights, densities, film or sampler (a PCG
// stream per pixel). Its rays/s against the raw rate is what the renderer's would be if its own
// work per ray cost nothing.
double bare_loop_rate(const Scene& scene, int threads, int spp) {
    return bare_rate(scene, threads, [&](const BareScene& bs, RTCIntersectContext& ctx, int y0, int y1) {
        uint64_t local = 0;
        for (int y = y0; y != y1; ++y)
            for (int x = 0; x < bs.w; ++x) {
                Rng rng = Rng::for_sample(3, uint64_t(y) * uint64_t(bs.w) + uint64_t(x), 0);
                for (int s = 0; s < spp; ++s) {
                    Ray ray = bs.sensor.generate_ray({x + rng.next_1d(), y + rng.next_1d()}, {0.f, 0.f});
                    for (int depth = 0; depth < 9; ++depth) {
                        RTCRayHit rh;
                        rh.ray = embree_ray(ray.o, ray.d, kInfinity);
                        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                        rtcIntersect1(bs.rtc, &ctx, &rh);
                        ++local;
                        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
                        Vec3 n = normalize(Vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
                        if (dot(n, ray.d) > 0) n = -n;
                        const Vec3 p = ray.o + ray.d * rh.ray.tfar + n * bs.eps;
                        RTCRay sr = embree_ray(p, bs.target - p, 1.f);
                        rtcOccluded1(bs.rtc, &ctx, &sr);
                        ++local;
                        const Vec3 l = square_to_cosine_hemisphere({rng.next_1d(), rng.next_1d()});
                        const Frame f = Frame::from_normal(n);
                        ray.o = p;
                        ray.d = f.to_world(l);
                    }
                }
            }
        return local;
    });
}

// The bare loop with 8 paths in flight per thread: each round traces every live path's next
// ray in one rtcIntersect8 and their shadow rays in one rtcOccluded8, and a path that ends hands
// its lane to the next (pixel, sample). Rays of the same kind as bare_loop_rate's (camera rays,
// cosine bounces, shadow rays to the box's centre), so the ratio of the two is what batching
// could gain where ray queries were all the work.
double bare_packet_loop_rate(const Scene& scene, int threads, int spp) {
    return bare_rate(scene, threads, [&](const BareScene& bs, RTCIntersectContext& ctx, int y0, int y1) {
        uint64_t local = 0;
        struct Lane {
            bool live = false;
            int depth = 0;
            Ray ray;
            Rng rng{0, 0};
        } lanes[8];
        // The next (pixel, sample) in the bare loop's order, each sample with its own stream
        // (the samples of a pixel are in flight together).
        long long next = (long long)y0 * bs.w * spp;
        const long long end = (long long)y1 * bs.w * spp;
        const auto refill = [&](Lane& l) {
            if (next >= end) return;
            const long long pixel = next / spp;
            const int x = int(pixel % bs.w), y = int(pixel / bs.w);
            l.rng = Rng::for_sample(3, uint64_t(pixel), uint64_t(next % spp));
            l.ray = bs.sensor.generate_ray({x + l.rng.next_1d(), y + l.rng.next_1d()}, {0.f, 0.f});
            l.depth = 0;
            l.live = true;
            ++next;
        };
        for (Lane& l : lanes) refill(l);
        for (;;) {
            alignas(32) int valid[8];
            alignas(32) RTCRayHit8 rh;
            bool any = false;
            for (int k = 0; k < 8; ++k) {
                valid[k] = lanes[k].live ? -1 : 0;
                any |= lanes[k].live;
                if (!lanes[k].live) continue;
                const Ray& ray = lanes[k].ray;
                rh.ray.org_x[k] = ray.o.x; rh.ray.org_y[k] = ray.o.y; rh.ray.org_z[k] = ray.o.z;
                rh.ray.dir_x[k] = ray.d.x; rh.ray.dir_y[k] = ray.d.y; rh.ray.dir_z[k] = ray.d.z;
                rh.ray.tnear[k] = 0; rh.ray.tfar[k] = kInfinity; rh.ray.mask[k] = ~0u;
                rh.ray.flags[k] = 0; rh.ray.time[k] = 0; rh.ray.id[k] = unsigned(k);
                rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
            }
            if (!any) break;
            rtcIntersect8(valid, bs.rtc, &ctx, &rh);
            alignas(32) int svalid[8];
            alignas(32) RTCRay8 sr;
            Vec3 p[8], n[8];
            for (int k = 0; k < 8; ++k) {
                svalid[k] = 0;
                if (!valid[k]) continue;
                ++local;
                if (rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) {
                    lanes[k].live = false;
                    continue;
                }
                const Ray& ray = lanes[k].ray;
                n[k] = normalize(Vec3(rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]));
                if (dot(n[k], ray.d) > 0) n[k] = -n[k];
                p[k] = ray.o + ray.d * rh.ray.tfar[k] + n[k] * bs.eps;
                const Vec3 d = bs.target - p[k];
                svalid[k] = -1;
                sr.org_x[k] = p[k].x; sr.org_y[k] = p[k].y; sr.org_z[k] = p[k].z;
                sr.dir_x[k] = d.x; sr.dir_y[k] = d.y; sr.dir_z[k] = d.z;
                sr.tnear[k] = 0; sr.tfar[k] = 1.f; sr.mask[k] = ~0u; sr.flags[k] = 0; sr.time[k] = 0;
                sr.id[k] = unsigned(k);
            }
            rtcOccluded8(svalid, bs.rtc, &ctx, &sr);
            for (int k = 0; k < 8; ++k) {
                Lane& l = lanes[k];
                if (svalid[k]) {
                    ++local;
                    const Vec3 dl = square_to_cosine_hemisphere({l.rng.next_1d(), l.rng.next_1d()});
                    l.ray.o = p[k];
                    l.ray.d = Frame::from_normal(n[k]).to_world(dl);
                    if (++l.depth == 9) l.live = false;
                }
                if (!l.live) refill(l);
            }
        }
        return local;
    });
}

struct Spread {
    double median, lo, hi;
};
Spread spread(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return {n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]), v.front(), v.back()};
}

// REPEATS renders, each followed by Embree's raw rate for at least 1.5x its rays (1e6 per thread
// at the least), so a ratio always compares two measurements taken back to back.
struct Paired {
    Spread samples_per_s, rays_per_s, embree, ratio;
};
Paired paired_rates(const Scene& scene, int threads, long long spp, int repeats) {
    std::vector<double> samples, rays, embree, ratio;
    for (int k = 0; k < repeats; ++k) {
        const Rate r = render_rate(scene, threads, spp);
        const double e = embree_raw_rate(scene, threads, (long long)std::max(1e6 * threads, r.rays_per_s * 1.5));
        samples.push_back(r.samples_per_s);
        rays.push_back(r.rays_per_s);
        embree.push_back(e);
        ratio.push_back(r.rays_per_s / e);
    }
    return {spread(samples), spread(rays), spread(embree), spread(ratio)};
}

std::string range(const Spread& s) { return fmt::format("{:.3f}-{:.3f}", s.lo, s.hi); }

}  // namespace

int main(int argc, char** argv) {
    std::string path = argc > 1 ? argv[1] : OMEGA_SOURCE_DIR "/scenes/cornell-box.yaml";
    long long spp = argc > 2 ? std::stoll(argv[2]) : 32;
    // Thread counts 1, 2, 4, ... up to N (argv[3], default: every hardware thread), N included.
    const int max_threads = argc > 3 ? std::max(1, std::stoi(argv[3])) : std::max(1, int(std::thread::hardware_concurrency()));
    const int repeats = argc > 4 ? std::max(1, std::stoi(argv[4])) : 3;
    // The film's side: 256 keeps a run short; a scene's own size (1024 for the Cornell box)
    // shows how its splats spread over bands and tiles at the resolution people render at.
    const int size = argc > 5 ? std::max(8, std::stoi(argv[5])) : 256;
    std::vector<int> counts;
    for (int n = 1; n < max_threads; n *= 2) counts.push_back(n);
    counts.push_back(max_threads);
    SceneDesc desc = parse_scene_file(path);
    desc.sensor.film.width = desc.sensor.film.height = size;
    desc.sensor.film.has_crop = false;
    desc.integrator.type = IntegratorType::Path;
    desc.integrator.max_depth = 9;
    auto scene = Scene::build(desc);

    render_rate(*scene, max_threads, 2);  // warm-up: page in the BVH and the allocator
    fmt::print("scene {}  {}x{}  max_depth 9  {} spp  medians of {} alternating runs\n", path, size, size, spp, repeats);
    fmt::print("{:>10} {:>14} {:>14} {:>16} {:>12} {:>14} {:>18} {:>16}\n", "threads", "Msamples/s", "Mrays/s",
               "Embree Mrays/s", "ratio", "ratio range", "speedup renderer", "speedup Embree");
    Paired p1{};
    double e_max = 0;
    for (int n : counts) {
        // Each count renders the same samples, so the speedup is a ratio of rates in this run.
        const Paired p = paired_rates(*scene, n, spp, repeats);
        if (n == 1) p1 = p;
        e_max = p.embree.median;
        fmt::print("{:>10} {:>14.3f} {:>14.3f} {:>16.3f} {:>12.3f} {:>14} {:>18.2f} {:>16.2f}\n", n,
                   p.samples_per_s.median / 1e6, p.rays_per_s.median / 1e6, p.embree.median / 1e6, p.ratio.median,
                   range(p.ratio), p.samples_per_s.median / p1.samples_per_s.median, p.embree.median / p1.embree.median);
    }
    fmt::print("speedup 1 -> {} threads below 0.9 x {} means something is shared that should not be\n", max_threads,
               max_threads);
    std::vector<double> bares;
    for (int k = 0; k < repeats; ++k) bares.push_back(bare_loop_rate(*scene, max_threads, int(std::max(1LL, spp / 4))));
    const double bare = spread(bares).median;
    std::vector<double> batched;
    for (int k = 0; k < repeats; ++k)
        batched.push_back(bare_packet_loop_rate(*scene, max_threads, int(std::max(1LL, spp / 4))) /
                          bare_loop_rate(*scene, max_threads, int(std::max(1LL, spp / 4))));
    const Spread batch = spread(batched);
    fmt::print("bare one-ray loop (Embree, a cosine bounce and a shadow ray per hit, nothing else): {:.3f} Mrays/s, "
               "{:.3f} of Embree's raw rate: the ceiling for a tracer that issues one ray at a time\n",
               bare / 1e6, bare / e_max);
    fmt::print("bare loop with 8 paths in flight per thread (rtcIntersect8, rtcOccluded8): {:.3f} ({:.3f}-{:.3f}) x the "
               "one-ray loop's rate: the ceiling of batching\n", batch.median, batch.lo, batch.hi);

    // The headroom of batching: Embree's rate on the same incoherent rays in packets of 8, each
    // run alternating with the single-ray one.
    std::vector<double> packet_ratios;
    const long long packet_rays = (long long)std::max(2e6 * max_threads, e_max);  // about a second
    for (int k = 0; k < repeats; ++k) {
        const double single = embree_raw_rate(*scene, max_threads, packet_rays);
        packet_ratios.push_back(embree_raw_rate(*scene, max_threads, packet_rays, true) / single);
    }
    const Spread packet = spread(packet_ratios);
    fmt::print("Embree in packets of 8 (rtcIntersect8, the same rays): {:.3f} ({:.3f}-{:.3f}) x its single-ray rate: "
               "what a tracer that batched 8 paths' rays (Scene::intersect_packet) would gain on its ray queries\n",
               packet.median, packet.lo, packet.hi);

    // The splatting integrators on the same scene and BVH, all threads, in the same run: their
    // rays/s against Embree's raw rate shows how much of their time is bookkeeping (densities,
    // MIS, splats) rather than ray queries. Each renders SPP samples, as the thread counts above
    // do: at SPP / 8 (2 at the usual 16) a path-tracing run lasted 65 ms and a splatting one two
    // batches, so start-up (threads, the first pass's cold caches and index order, the first
    // batch's band cut) weighed in every figure and spread them over +-2%.
    fmt::print("{:>10} {:>14} {:>14} {:>16} {:>12} {:>14} {:>14}\n", "integrator", "Msamples/s", "Mrays/s", "rays/sample",
               "vs Embree", "range", "samples vs path");
    std::vector<std::pair<IntegratorType, Paired>> rates;
    for (IntegratorType t : {IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt}) {
        SceneDesc d = desc;
        d.integrator.type = t;
        auto sc = Scene::build(d);
        const Paired p = paired_rates(*sc, max_threads, spp, repeats);
        const double path_samples = rates.empty() ? p.samples_per_s.median : rates.front().second.samples_per_s.median;
        fmt::print("{:>10} {:>14.3f} {:>14.3f} {:>16.1f} {:>12.3f} {:>14} {:>14.3f}\n", integrator_name(t),
                   p.samples_per_s.median / 1e6, p.rays_per_s.median / 1e6, p.rays_per_s.median / p.samples_per_s.median,
                   p.ratio.median, range(p.ratio), p.samples_per_s.median / path_samples);
        rates.emplace_back(t, p);
    }

    // What the targets (issue 12: 0.85 of Embree's raw rate for path, 0.6 for the others) ask of
    // the renderer's own work per ray, in ns per ray per thread: a ray costs the bare loop's time
    // (Embree on these rays) plus that work, so the work must fit in raw / target - bare.
    const auto ns = [&](double rays_per_s) { return 1e9 * max_threads / rays_per_s; };
    fmt::print("ns per ray per thread: Embree raw {:.0f}, bare loop {:.0f}\n", ns(e_max), ns(bare));
    fmt::print("{:>10} {:>8} {:>12} {:>14} {:>14} {:>12}\n", "integrator", "target", "ns per ray", "own work (ns)",
               "allowed (ns)", "cut needed");
    for (const auto& [t, p] : rates) {
        const double target = t == IntegratorType::Path ? 0.85 : 0.6;
        const double own = ns(p.rays_per_s.median) - ns(bare), allowed = ns(p.embree.median) / target - ns(bare);
        fmt::print("{:>10} {:>8.2f} {:>12.0f} {:>14.0f} {:>14.0f} {:>11.0f}%\n", integrator_name(t), target,
                   ns(p.rays_per_s.median), own, allowed, own > allowed ? 100.0 * (1.0 - allowed / own) : 0.0);
    }

    // The schedule model: what each integrator's parallel structure allows on N threads, from a
    // one-thread record, beside the speedup measured on this machine's threads (same spp).
    fmt::print("schedule model (1-thread record replayed on N workers; an upper bound: no shared caches or memory "
               "bandwidth), medians of {}\n", repeats);
    fmt::print("{:>10} {:>8} {:>10} {:>10} {:>12}", "integrator", "spp", "serial %", "idle % @16", "measured @" + std::to_string(max_threads));
    const std::vector<int> model_counts = {2, 4, 8, 16};
    for (int n : model_counts) fmt::print(" {:>9}", fmt::format("model @{}", n));
    fmt::print("\n");
    for (IntegratorType t : {IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt}) {
        SceneDesc d = desc;
        d.integrator.type = t;
        auto sc = Scene::build(d);
        // Half the spp for the splatting integrators: one batch per sample index, and enough
        // batches that one disturbed task does not decide a barrier.
        const long long n_spp = t == IntegratorType::Path ? spp : std::max(1LL, spp / 2);
        std::vector<double> serial, idle, measured, ideal, by_item;
        std::vector<std::vector<double>> model(model_counts.size());
        std::vector<std::pair<std::string, std::vector<double>>> idle_by_kind;  // % of 16 x the time
        for (int k = 0; k < repeats; ++k) {
            ScheduleProbe probe;
            render_rate(*sc, 1, n_spp, &probe);
            const double t1 = probe.predict(1).seconds;
            serial.push_back(100.0 * probe.predict(1).serial_s / t1);
            const auto p16 = probe.predict(16);
            idle.push_back(100.0 * p16.idle_s / (16.0 * p16.seconds));
            ideal.push_back(t1 / probe.predict(16, ScheduleProbe::Order::LongestFirst).seconds);
            by_item.push_back(t1 / probe.predict(16, ScheduleProbe::Order::ByItem).seconds);
            for (const auto& kind : p16.kinds) {
                auto it = std::find_if(idle_by_kind.begin(), idle_by_kind.end(), [&](const auto& e) { return e.first == kind.kind; });
                if (it == idle_by_kind.end()) it = idle_by_kind.insert(idle_by_kind.end(), {kind.kind, {}});
                it->second.push_back(100.0 * kind.idle_s / (16.0 * p16.seconds));
            }
            for (size_t i = 0; i < model_counts.size(); ++i) model[i].push_back(t1 / probe.predict(model_counts[i]).seconds);
            if (max_threads > 1)
                measured.push_back(render_rate(*sc, max_threads, n_spp).samples_per_s / render_rate(*sc, 1, n_spp).samples_per_s);
        }
        fmt::print("{:>10} {:>8} {:>10.2f} {:>10.2f} {:>12}", integrator_name(t), n_spp, spread(serial).median,
                   spread(idle).median, measured.empty() ? std::string("-") : fmt::format("{:.2f}", spread(measured).median));
        for (auto& m : model) fmt::print(" {:>9.2f}", spread(m).median);
        std::string kinds;
        for (const auto& [kind, v] : idle_by_kind) kinds += fmt::format(" {} {:.1f}%", kind, spread(v).median);
        fmt::print("   @16 with each region's tasks in index order {:.2f}, longest first {:.2f}; idle @16 by region:{}\n",
                   spread(by_item).median, spread(ideal).median, kinds);
    }
    return 0;
}
