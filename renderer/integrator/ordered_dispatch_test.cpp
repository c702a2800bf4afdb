// Tiles handed out longest first: the order, and a dispatch that starts items in it.
#include "integrator/ordered_dispatch.h"

#include <gtest/gtest.h>

#include <mutex>

namespace omega {
namespace {

TEST(LongestFirst, OrdersByLastCostThenUnrunItemsByIndex) {
    LongestFirst lf;
    lf.resize(5);
    EXPECT_EQ(lf.order(), (std::vector<uint32_t>{0, 1, 2, 3, 4}));  // nothing ran yet: index order
    lf.record(3, 2.0);
    lf.record(1, 5.0);
    lf.record(4, 2.0);
    EXPECT_EQ(lf.order(), (std::vector<uint32_t>{1, 3, 4, 0, 2}));  // ties keep index order
    lf.resize(5);  // same size: the costs stay
    EXPECT_EQ(lf.order().front(), 1u);
    lf.resize(2);  // another film: forgotten
    EXPECT_EQ(lf.order(), (std::vector<uint32_t>{0, 1}));
}

TEST(ForEachOrdered, StartsItemsInTheOrderGivenAndStopsWhenTold) {
    tbb::task_arena one(1);
    const std::vector<uint32_t> order{4, 0, 3, 1, 2};
    std::vector<uint32_t> seen;
    for_each_ordered(one, order, [&](uint32_t i) {
        seen.push_back(i);
        return true;
    });
    EXPECT_EQ(seen, order);
    seen.clear();
    for_each_ordered(one, order, [&](uint32_t i) {
        seen.push_back(i);
        return i != 3;  // a pass cut at its time limit
    });
    EXPECT_EQ(seen, (std::vector<uint32_t>{4, 0, 3}));

    // Several workers: every item exactly once.
    tbb::task_arena four(4);
    std::vector<uint32_t> many(1000);
    for (uint32_t i = 0; i < many.size(); ++i) many[i] = uint32_t(many.size()) - 1 - i;
    std::vector<int> count(many.size(), 0);
    std::mutex m;
    for_each_ordered(four, many, [&](uint32_t i) {
        std::lock_guard<std::mutex> lock(m);
        ++count[i];
        return true;
    });
    for (int c : count) EXPECT_EQ(c, 1);
}

}  // namespace
}  // namespace omega
