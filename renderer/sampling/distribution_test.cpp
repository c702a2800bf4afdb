#include "sampling/distribution.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "chi2.h"
#include "sampling/rng.h"

namespace omega {
namespace {

TEST(DiscreteDistribution, ChiSquareOverItems) {
    // Includes zero weights (must never be drawn) and a tiny one (pooled by the harness).
    std::vector<double> w = {1, 0, 3, 0.5, 7, 0, 2, 1e-4, 4, 0.25};
    DiscreteDistribution d(w);
    const size_t n = 1'000'000;
    std::vector<double> observed(w.size(), 0.0), expected(w.size());
    double total = 0;
    for (double x : w) total += x;
    for (size_t i = 0; i < w.size(); ++i) expected[i] = w[i] / total * double(n);
    Rng rng(3, 0);
    for (size_t s = 0; s < n; ++s) {
        float u_remapped = -1;
        size_t i = d.sample(rng.next_1d(), &u_remapped);
        ASSERT_LT(i, w.size());
        ASSERT_GE(u_remapped, 0.f);
        ASSERT_LT(u_remapped, 1.f);
        observed[i] += 1;
    }
    test::Chi2Result r = test::chi2_from_counts(observed, expected, 0.01, 2);
    test::print_result("DiscreteDistribution", r);
    EXPECT_TRUE(r.passed) << r.message;
    EXPECT_EQ(observed[1], 0);
    EXPECT_EQ(observed[5], 0);
    for (size_t i = 0; i < w.size(); ++i) EXPECT_NEAR(d.pmf(i), w[i] / total, 1e-7);
}

TEST(DiscreteDistribution, RemappedUIsUniform) {
    // The rescaled u is reused by callers; it must be uniform within the chosen item.
    DiscreteDistribution d({1, 2, 3});
    const size_t n = 200'000;
    const int bins = 50;
    std::vector<double> observed(bins, 0.0), expected(bins, double(n) / bins);
    Rng rng(5, 0);
    for (size_t s = 0; s < n; ++s) {
        float u2;
        d.sample(rng.next_1d(), &u2);
        observed[std::min(bins - 1, int(u2 * bins))] += 1;
    }
    test::Chi2Result r = test::chi2_from_counts(observed, expected, 0.01, 2);
    test::print_result("DiscreteDistribution remapped u", r);
    EXPECT_TRUE(r.passed) << r.message;
}

TEST(DiscreteDistribution, HarnessRejectsWrongPmf) {
    std::vector<double> w = {1, 2, 3, 4};
    DiscreteDistribution d(w);
    std::vector<double> observed(4, 0.0);
    Rng rng(9, 0);
    for (size_t s = 0; s < 200'000; ++s) observed[d.sample(rng.next_1d())] += 1;
    // Claim item 0 is 10% likelier than it is (renormalised).
    std::vector<double> expected = {1.1, 2, 3, 4};
    for (double& e : expected) e *= 200'000 / 10.1;
    EXPECT_FALSE(test::chi2_from_counts(observed, expected, 0.01, 1).passed);
}

// Small distributions are searched by a scan, larger ones by binary search: both must pick the
// entry upper_bound picks, at item boundaries too.
TEST(DiscreteDistribution, ScanAndBinarySearchPickTheSameItem) {
    Rng rng(17, 0);
    for (size_t n = 1; n <= 12; ++n) {
        std::vector<double> w(n);
        for (size_t i = 0; i < n; ++i) w[i] = (i % 3 == 1) ? 0.0 : 0.1 + rng.next_1d();
        if (n == 1) w[0] = 1;
        // Even n: integer weights summing to 32 put the cdf on floats, so u lands exactly on
        // item boundaries, where only a strict comparison picks upper_bound's item.
        if (n % 2 == 0) {
            double partial = 0;
            for (size_t i = 0; i + 1 < n; ++i) partial += w[i] = (i % 3 == 1) ? 0.0 : double(1 + i % 4);
            w[n - 1] = 32.0 - partial;  // the sum is 32
        }
        DiscreteDistribution d(w);
        double sum = 0;
        for (double x : w) sum += x;
        std::vector<double> cdf(n);
        double acc = 0;
        for (size_t i = 0; i < n; ++i) cdf[i] = acc += w[i] / sum;
        cdf.back() = 1.0;
        std::vector<float> us;
        for (int k = 0; k < 1000; ++k) us.push_back(rng.next_1d());
        for (double c : cdf) us.push_back(float(c)), us.push_back(std::nextafter(float(c), 0.f));
        us.push_back(0.f);
        for (float u : us) {
            if (!(u < 1.f)) continue;
            size_t want = size_t(std::min<ptrdiff_t>(std::upper_bound(cdf.begin(), cdf.end(), double(u)) - cdf.begin(), ptrdiff_t(n) - 1));
            while (w[want] == 0 && want > 0) --want;
            ASSERT_EQ(d.sample(u), want) << "n " << n << " u " << u;
        }
    }
}

TEST(DiscreteDistribution, DegenerateInputs) {
    EXPECT_TRUE(DiscreteDistribution(std::vector<double>{}).empty());
    EXPECT_TRUE(DiscreteDistribution({0.0, 0.0}).empty());
    DiscreteDistribution one({0.0, 5.0, 0.0});
    for (float u : {0.f, 0.3f, 0.999999f}) EXPECT_EQ(one.sample(u), 1u);
    // One item (a scene's one light) skips the search: the same index, and remapping still works.
    DiscreteDistribution single({2.5});
    for (float u : {0.f, 0.3f, 0.999999f}) {
        EXPECT_EQ(single.sample(u), 0u);
        float r = -1.f;
        EXPECT_EQ(single.sample(u, &r), 0u);
        EXPECT_EQ(r, u);
    }
    EXPECT_EQ(single.pmf(0), 1.f);
}

}  // namespace
}  // namespace omega
