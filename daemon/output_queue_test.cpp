#include "daemon/output_queue.h"

#include <gtest/gtest.h>

namespace omega::daemon {
namespace {

std::string drain(OutputQueue& q, std::size_t chunk = 1 << 20) {
  std::string out;
  while (!q.empty()) {
    iovec iov[16];
    int n = q.fill_iov(iov, 16);
    std::size_t took = 0;
    for (int i = 0; i < n && took < chunk; ++i) {
      std::size_t k = std::min(iov[i].iov_len, chunk - took);
      out.append(static_cast<const char*>(iov[i].iov_base), k);
      took += k;
    }
    q.consume(took);
  }
  return out;
}

auto body(const char* s) { return std::make_shared<const std::string>(s); }

TEST(OutputQueue, CoalescesByKeyKeepingThePlace) {
  OutputQueue q;
  q.push("A");
  q.push_coalesced({1, 7, 0}, "t0:", body("v1"));
  q.push_coalesced({1, 7, 1}, "t1:", body("v1"));
  q.push_coalesced({1, 7, 0}, "t0:", body("v2"));  // replaces in place
  q.push("B");
  EXPECT_EQ(q.frames(), 4u);
  EXPECT_EQ(q.coalesced_replacements(), 1u);
  EXPECT_EQ(drain(q), "At0:v2t1:v1B");
}

TEST(OutputQueue, NeverReplacesAFramePartlyWritten) {
  OutputQueue q;
  q.push_coalesced({1, 7, 0}, "head", body("old"));
  iovec iov[4];
  ASSERT_GE(q.fill_iov(iov, 4), 1);
  q.consume(2);  // "he" is on the wire
  q.push_coalesced({1, 7, 0}, "head", body("new"));
  EXPECT_EQ(drain(q, 3), "adoldheadnew");
}

TEST(OutputQueue, CountsOnlyOwnedBytesAgainstTheLimit) {
  OutputQueue q;
  q.push(std::string(100, 'x'));
  q.push_coalesced({1, 1, 0}, "h", std::make_shared<const std::string>(1000, 'y'));
  EXPECT_EQ(q.owned_bytes(), 100u);
  drain(q, 7);
  EXPECT_EQ(q.owned_bytes(), 0u);
  EXPECT_TRUE(q.empty());
}

TEST(OutputQueue, DistinctSubscriptionsDoNotCoalesce) {
  OutputQueue q;
  q.push_coalesced({1, 7, 0}, "a", nullptr);
  q.push_coalesced({2, 7, 0}, "b", nullptr);
  q.push_coalesced({1, 7, kProgressSlot}, "p", nullptr);
  q.push_coalesced({1, 7, kProgressSlot}, "q", nullptr);
  EXPECT_EQ(drain(q), "abq");
}

}  // namespace
}  // namespace omega::daemon
