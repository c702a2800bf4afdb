// The breakdown's parts that need no render: exact sums, class keys, the statistics.
#include "integrator/breakdown.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "integrator/path_class.h"
#include "pathspace/path_signature.h"

namespace omega {
namespace {

TEST(ExactSum, SameBitsInAnyOrderAndGrouping) {
    std::mt19937_64 rng(7);
    std::vector<double> terms;
    for (int i = 0; i < 5000; ++i) {
        const double mag = std::ldexp(1.0, int(rng() % 120) - 60);
        terms.push_back((rng() % 2 ? 1 : -1) * mag * std::uniform_real_distribution<double>(0.5, 1)(rng));
    }
    ExactSum a;
    for (double t : terms) a.add(t);
    std::shuffle(terms.begin(), terms.end(), rng);
    ExactSum b, c;
    for (size_t i = 0; i < terms.size(); ++i) (i % 3 ? b : c).add(terms[i]);
    b.add(c);
    EXPECT_EQ(a.digits(), b.digits());
    EXPECT_EQ(a.value(), b.value());
    // A plain double sum differs with the order; the exact one is the correctly ordered value.
    long double ref = 0;
    for (double t : terms) ref += t;
    EXPECT_NEAR(a.value(), double(ref), 1e-12 * std::abs(double(ref)) + 1e-30);
}

TEST(ExactSum, TextRoundTrips) {
    for (double v : {0.0, 1.0, -3.5e-90, 7.25e90, 1e-300}) {
        ExactSum a;
        a.add(v);
        a.add(-0.25);
        ExactSum b;
        b.set_text(a.text());
        EXPECT_EQ(a.digits(), b.digits()) << a.text();
    }
    ExactSum n;
    n.add(1e200 * 1e200);
    ExactSum m;
    m.set_text(n.text());
    EXPECT_TRUE(m.overflowed());
    EXPECT_THROW(m.set_text("3:zz"), std::invalid_argument);
    EXPECT_THROW(m.set_text("99:1"), std::invalid_argument);
}

TEST(ExactSum, CancellationAndOverflow) {
    ExactSum s;
    s.add(1e90);
    s.add(1.0);
    s.add(-1e90);
    EXPECT_EQ(s.value(), 1.0);
    s.add(1e100);  // beyond the range: no value rather than a wrong one
    EXPECT_TRUE(std::isnan(s.value()));
}

TEST(PathClass, KeysAndNames) {
    // L D S E: light first x1 = D, x2 = S; eye first vertex 1 = S.
    const std::vector<VertexClass> sig{VertexClass::L, VertexClass::D, VertexClass::S, VertexClass::E};
    const PathClassKey k = path_class_key(sig, 6);
    EXPECT_EQ(path_class_name(k), "L D S E");
    EXPECT_EQ(path_class_length(k), 3);
    // G counts as D; the mirror vertex goes after the given index.
    const std::vector<VertexClass> sig2{VertexClass::L, VertexClass::G, VertexClass::E};
    EXPECT_EQ(path_class_name(path_class_key(sig2, 6)), "L D E");
    EXPECT_EQ(path_class_key(sig2, 6, 1), k);
    EXPECT_EQ(path_class_key(sig, 2), kLongerClass);
    // The path tracer's walk gives the same keys: E, scatter S at vertex 1, NEE from vertex 2 (D).
    PathClassTracker t(6);
    t.reset();
    t.scatter(1, true);
    t.emit_via(2, Rgb(1.f));  // L D S E
    t.emit(2, Rgb(1.f));      // L S E
    t.emit_via_mirror(1, Rgb(1.f));  // E, D at 1, mirror S at 2, L: L S D E
    ASSERT_EQ(t.contributions().size(), 3u);
    EXPECT_EQ(t.contributions()[0].first, k);
    EXPECT_EQ(path_class_name(t.contributions()[1].first), "L S E");
    EXPECT_EQ(path_class_name(t.contributions()[2].first), "L S D E");
}

// The BDPT tracer's keys from delta bits equal the keys of the full signatures that
// strategy_signature and lens_signature build (the light path expressions' classes).
TEST(PathClass, DeltaBitKeysMatchSignatures) {
    std::mt19937_64 rng(3);
    std::vector<VertexClass> sig;
    for (int trial = 0; trial < 200; ++trial) {
        std::vector<PathVertex> light(8), camera(8);
        uint64_t ld = 0, cd = 0;
        for (int i = 1; i < 8; ++i) {
            light[size_t(i)].delta = rng() % 2;
            camera[size_t(i)].delta = rng() % 2;
            if (light[size_t(i)].delta) ld |= uint64_t(1) << (i - 1);
            if (camera[size_t(i)].delta) cd |= uint64_t(1) << (i - 1);
        }
        for (int s = 0; s <= 7; ++s)
            for (int t = 1; t <= 7; ++t) {
                if (s + t - 1 < 1) continue;
                strategy_signature(light, camera, s, t, sig);
                EXPECT_EQ(strategy_class_key(ld, cd, s, t, false, 16), path_class_key(sig, 16)) << s << " " << t;
                if (s >= 1) {
                    EXPECT_EQ(strategy_class_key(ld, cd, s, t, true, 16), path_class_key(sig, 16, s - 1)) << s << " " << t;
                }
            }
        for (int s = 1; s <= 7; ++s) {
            lens_signature(light, s, sig);
            EXPECT_EQ(lens_class_key(ld, s, 16), path_class_key(sig, 16)) << s;
        }
    }
}

TEST(BreakdownStats, FractionAndErrors) {
    // Units alternate: class A carries 1, class B carries 3. Fractions 1/4 and 3/4 with zero
    // spread of X_c - f X_T only if every unit had the same mix: here they differ.
    const PathClassKey a = path_class_key(1, 0, 6), b = path_class_key(2, 0, 6);
    BreakdownStats s;
    BreakdownUnit u;
    for (int i = 0; i < 1000; ++i) {
        u.clear();
        if (i % 2) u.add(a, 1.0);
        else u.add(b, 3.0);
        s.add_unit(u);
    }
    s.add_empty_unit();
    const BreakdownReport r = make_breakdown_report(s, "image", 6);
    const auto classes = r.of_kind("class");
    ASSERT_EQ(classes.size(), 2u);
    EXPECT_NEAR(classes[0]->fraction, 0.25, 1e-15);
    EXPECT_NEAR(classes[0]->mu, 500.0 / 1001, 1e-12);
    EXPECT_GT(classes[0]->fraction_stderr, 0.005);
    EXPECT_LT(classes[0]->fraction_stderr, 0.05);
    EXPECT_EQ(r.units, 1001u);
    const auto back = parse_breakdown_csv(breakdown_csv(r));
    ASSERT_EQ(back.rows.size(), r.rows.size());
    EXPECT_EQ(back.rows[0].name, "L E");
    EXPECT_THROW(parse_breakdown_csv("nonsense\n"), std::invalid_argument);
    // The exact state round-trips to the same report.
    const BreakdownState st = parse_breakdown_state(breakdown_state_text({"image", 6, s}));
    EXPECT_EQ(breakdown_csv(make_breakdown_report(st.stats, st.region, st.max_length)), breakdown_csv(r));
    EXPECT_THROW(parse_breakdown_state("region image 6\nc 1 0 0\n"), std::invalid_argument);
}

}  // namespace
}  // namespace omega
