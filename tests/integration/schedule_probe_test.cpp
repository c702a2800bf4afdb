// The schedule model (integrator/schedule_probe.h): its replay on N workers, and what a real
// one-thread render records (one region per pass of tiles, four per splatting batch).
#include "integrator/schedule_probe.h"

#include <gtest/gtest.h>

#include <stdexcept>

#include "render_harness.h"

namespace omega {
namespace {

TEST(ScheduleProbe, ReplaysTasksInOrderOnTheWorkerThatFreesFirst) {
    ScheduleProbe p;
    p.add_region(0.5, {3, 1, 1, 1});
    p.set_tail(0.25);
    EXPECT_DOUBLE_EQ(p.predict(1).seconds, 6.75);
    EXPECT_DOUBLE_EQ(p.predict(1).serial_s, 0.75);
    EXPECT_DOUBLE_EQ(p.predict(1).idle_s, 0.0);
    // Two workers: 3 on one, 1 + 1 + 1 on the other.
    EXPECT_DOUBLE_EQ(p.predict(2).seconds, 3.75);
    EXPECT_DOUBLE_EQ(p.predict(2).idle_s, 0.0);
    // Four: the long task is the region; three workers wait 2 s each.
    EXPECT_DOUBLE_EQ(p.predict(4).seconds, 3.75);
    EXPECT_DOUBLE_EQ(p.predict(4).idle_s, 6.0);

    // In order, not the best packing: the long task last waits for a free worker (6, not 4).
    ScheduleProbe q;
    q.add_region(0, {1, 1, 1, 1, 4});
    EXPECT_DOUBLE_EQ(q.predict(2).seconds, 6.0);
    EXPECT_DOUBLE_EQ(q.predict(2).idle_s, 4.0);
    // Replayed by item (index order) or longest first, the same record packs differently.
    ScheduleProbe o;
    o.add_region(0, {1, 1, 1, 1, 4}, "tiles", {1, 2, 3, 4, 0});
    EXPECT_DOUBLE_EQ(o.predict(2).seconds, 6.0);
    EXPECT_DOUBLE_EQ(o.predict(2, ScheduleProbe::Order::ByItem).seconds, 4.0);
    EXPECT_DOUBLE_EQ(o.predict(2, ScheduleProbe::Order::LongestFirst).seconds, 4.0);
    EXPECT_DOUBLE_EQ(q.predict(2, ScheduleProbe::Order::ByItem).seconds, 6.0);  // default items: as run
    // Regions end at a barrier: two regions of one task each do not overlap.
    ScheduleProbe r;
    r.add_region(0, {2}, "tiles");
    r.add_region(0, {2}, "merge");
    r.add_region(0, {1, 1}, "tiles");
    EXPECT_DOUBLE_EQ(r.predict(8).seconds, 5.0);
    EXPECT_EQ(r.regions(), 3u);
    EXPECT_EQ(r.tasks(), 4u);
    // By kind, in order of first appearance.
    const auto k = r.predict(2).kinds;
    ASSERT_EQ(k.size(), 2u);
    EXPECT_STREQ(k[0].kind, "tiles");
    EXPECT_DOUBLE_EQ(k[0].seconds, 3.0);
    EXPECT_DOUBLE_EQ(k[0].idle_s, 2.0);
    EXPECT_STREQ(k[1].kind, "merge");
    EXPECT_DOUBLE_EQ(k[1].idle_s, 2.0);
}

struct Recorded {
    ScheduleProbe probe;
    PassReport report;
    std::unique_ptr<RenderSession> session;
};

std::unique_ptr<Recorded> record(const Scene& scene, const RenderSettings& rs) {
    auto r = std::make_unique<Recorded>();
    r->session = std::make_unique<RenderSession>(scene, rs);
    r->session->set_schedule_probe(&r->probe);
    r->probe.start();
    r->report = r->session->run();
    r->probe.stop();
    return r;
}

TEST(ScheduleProbe, RecordsEveryRegionAndTaskOfAOneThreadRender) {
    // 40 x 30 in 8 x 8 tiles: 5 x 4 = 20 tiles; SplatBands' 8-row bands: 4.
    constexpr size_t kTiles = 20, kBands = 4;
    for (IntegratorType type : {IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt}) {
        SCOPED_TRACE(integrator_name(type));
        SceneDesc d = test::metal_cube_scene(40, 30);
        d.integrator.type = type;
        d.integrator.max_depth = 4;
        auto scene = Scene::build(d);
        RenderSettings rs;
        rs.threads = 1;
        rs.tile_size = 8;
        rs.halt.spp = 6;
        rs.seed = 3;
        rs.integrator = d.integrator;
        auto rec = record(*scene, rs);
        const ScheduleProbe& p = rec->probe;
        ASSERT_EQ(rec->report.spp, 6);
        const auto kinds = p.predict(1).kinds;
        // After each pass, the film's error in chunks: one chunk for 1200 pixels.
        const size_t passes = size_t(rec->report.pass);
        if (type == IntegratorType::Path) {
            // Per pass, one region of tiles, every tile a task, then the error.
            EXPECT_EQ(p.regions(), 2 * passes);
            EXPECT_EQ(p.tasks(), (kTiles + 1) * passes);
            ASSERT_EQ(kinds.size(), 2u);
            EXPECT_STREQ(kinds[0].kind, "tiles");
            EXPECT_STREQ(kinds[1].kind, "error");
        } else {
            // Per batch (sample index): clear the bands, the tiles (one wave), merge, add; per
            // pass, the error.
            EXPECT_EQ(p.regions(), 4u * 6u + passes);
            // Each batch cuts its bands for 16 workers (SplatBands::relayout): the first, with
            // no counts yet, a row each (30), later ones into as many as a row each.
            EXPECT_GE(p.tasks(), (kTiles + 3 * 30u) + 5u * (kTiles + 3 * kBands) + passes);
            EXPECT_LE(p.tasks(), 6u * (kTiles + 3 * 30u) + passes);
            EXPECT_GT(p.tasks(), (kTiles + 3 * 30u) + 5u * (kTiles + 3 * kBands) + passes)
                << "no band was cut from the counts for 16 workers";
            ASSERT_EQ(kinds.size(), 4u);
            EXPECT_STREQ(kinds[0].kind, "bands");
            EXPECT_STREQ(kinds[1].kind, "tiles");
            EXPECT_STREQ(kinds[2].kind, "merge");
            EXPECT_STREQ(kinds[3].kind, "error");
        }
        // The replay on one worker is the recorded run; more workers never take longer, and
        // never less than the serial part plus the busy time shared out evenly.
        const auto one = p.predict(1);
        EXPECT_NEAR(one.seconds, p.recorded_seconds(), 1e-9 * p.recorded_seconds() + 1e-12);
        double last = one.seconds;
        for (int n : {2, 4, 16}) {
            const auto pn = p.predict(n);
            EXPECT_LE(pn.seconds, last * (1 + 1e-12));
            EXPECT_GE(pn.seconds * (1 + 1e-12), pn.serial_s + (one.seconds - one.serial_s) / n);
            EXPECT_GE(pn.idle_s, 0.0);
            last = pn.seconds;
        }
        // Recording changes nothing in the image.
        auto plain = test::render(d, 6, 3, 1, 8);
        EXPECT_TRUE(test::same_bits(rec->session->film(), plain.film()));
    }
}

TEST(ScheduleProbe, RefusedOnASessionOfMoreThanOneThread) {
    SceneDesc d = test::metal_cube_scene(16, 16);
    auto scene = Scene::build(d);
    RenderSettings rs;
    rs.threads = 2;
    rs.integrator = d.integrator;
    RenderSession session(*scene, rs);
    ScheduleProbe p;
    EXPECT_THROW(session.set_schedule_probe(&p), std::logic_error);
}

}  // namespace
}  // namespace omega
