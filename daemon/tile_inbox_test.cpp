#include "daemon/tile_inbox.h"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <thread>

namespace omega::daemon {
namespace {

using Clock = std::chrono::steady_clock;

// The batches a TileInbox delivers (loop thread), each as its tiles' tags (TileUpdate::pass) and
// when it came; the test's "render thread" waits for them.
struct Batches {
  std::mutex m;
  std::condition_variable cv;
  std::vector<std::vector<std::uint64_t>> tags;
  std::vector<Clock::time_point> at;

  void deliver(std::vector<TileUpdate> tiles) {
    std::vector<std::uint64_t> t;
    for (const auto& u : tiles) t.push_back(u.pass);
    std::lock_guard lock(m);
    tags.push_back(std::move(t));
    at.push_back(Clock::now());
    cv.notify_all();
  }
  // Waits (up to a minute: sanitizer builds on a loaded machine) for the n-th batch.
  Clock::time_point wait(std::size_t n) {
    std::unique_lock lock(m);
    EXPECT_TRUE(cv.wait_for(lock, std::chrono::seconds(60), [&] { return tags.size() >= n; })) << n;
    return tags.size() >= n ? at[n - 1] : Clock::now();
  }
};

TileUpdate tile(std::uint64_t job, std::uint64_t tag, bool first = false) {
  TileUpdate t;
  t.job = job;
  t.pass = tag;
  t.first = first;
  return t;
}

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// Runs the loop on this thread while `render` plays the render threads, then stops it.
template <class Fn>
void with_loop(EventLoop& loop, Fn render) {
  std::thread t([&] {
    render();
    loop.post([&] { loop.stop(); });
  });
  loop.run();
  t.join();
}

TEST(TileInbox, FirstTileAtOnceThenBatchesThenQuietAgain) {
  EventLoop loop;
  Batches b;
  const double batch_s = 2.0;
  TileInbox inbox(loop, batch_s, [&](std::vector<TileUpdate> t) { b.deliver(std::move(t)); });
  with_loop(loop, [&] {
    auto t0 = Clock::now();
    inbox.push(tile(1, 1));
    // Delivered without waiting for a batch (well under batch_s, however slow the machine).
    const auto first = b.wait(1);
    EXPECT_LT(seconds(first - t0), batch_s / 2);
    // While tiles keep coming they share the next batch, due batch_s after the first.
    inbox.push(tile(1, 2));
    inbox.push(tile(1, 3));
    EXPECT_GE(seconds(b.wait(2) - first), batch_s * 0.9);
    // The timer after that finds nothing: quiet again, so the next tile goes at once.
    std::this_thread::sleep_for(std::chrono::duration<double>(batch_s * 1.5));
    t0 = Clock::now();
    inbox.push(tile(1, 4));
    EXPECT_LT(seconds(b.wait(3) - t0), batch_s / 2);
  });
  ASSERT_EQ(b.tags.size(), 3u);
  EXPECT_EQ(b.tags[0], std::vector<std::uint64_t>{1});
  EXPECT_EQ(b.tags[1], (std::vector<std::uint64_t>{2, 3}));
  EXPECT_EQ(b.tags[2], std::vector<std::uint64_t>{4});
}

TEST(TileInbox, AJobsFirstTileDoesNotWaitForAnotherJobsBatch) {
  EventLoop loop;
  Batches b;
  const double batch_s = 30.0;  // never reached: both deliveries must come before it
  TileInbox inbox(loop, batch_s, [&](std::vector<TileUpdate> t) { b.deliver(std::move(t)); });
  with_loop(loop, [&] {
    inbox.push(tile(1, 1, true));
    b.wait(1);
    inbox.push(tile(1, 2));        // waits for job 1's batch
    inbox.push(tile(2, 3, true));  // job 2's first: goes now, and takes what waits along
    const auto t0 = Clock::now();
    EXPECT_LT(seconds(b.wait(2) - t0), batch_s / 2);
  });
  ASSERT_EQ(b.tags.size(), 2u);
  EXPECT_EQ(b.tags[1], (std::vector<std::uint64_t>{2, 3}));
}

TEST(TileInbox, DrainDeliversWhatWaitsBeforeWhatFollows) {
  EventLoop loop;
  Batches b;
  std::vector<std::string> order;  // loop thread only
  TileInbox inbox(loop, 30.0, [&](std::vector<TileUpdate> t) {
    for (const auto& u : t) order.push_back("tile " + std::to_string(u.pass));
    b.deliver(std::move(t));
  });
  with_loop(loop, [&] {
    inbox.push(tile(1, 1));
    b.wait(1);
    inbox.push(tile(1, 2));
    // What a pass boundary does (Server::on_pass): the waiting tile first, then the progress.
    loop.post([&] {
      inbox.drain();
      order.push_back("progress");
    });
    b.wait(2);
  });
  EXPECT_EQ(order, (std::vector<std::string>{"tile 1", "tile 2", "progress"}));
}

}  // namespace
}  // namespace omega::daemon
