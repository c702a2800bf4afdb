#pragma once
// One epoll loop on one thread (the "loop thread") owns every socket. Other threads hand it work
// with post(), which wakes it through an eventfd.
#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

namespace omega::daemon {

class EventLoop {
 public:
  using Handler = std::function<void(std::uint32_t events)>;
  using Clock = std::chrono::steady_clock;

  EventLoop();  // throws std::system_error
  ~EventLoop();
  EventLoop(const EventLoop&) = delete;
  EventLoop& operator=(const EventLoop&) = delete;

  // Loop thread (or before run()). A handler may add or remove any fd, itself included.
  void add(int fd, std::uint32_t events, Handler h);
  void modify(int fd, std::uint32_t events);
  void remove(int fd);

  // Loop thread: fn runs once, `seconds` from now. Returns an id for cancel_timer().
  std::uint64_t add_timer(double seconds, std::function<void()> fn);
  void cancel_timer(std::uint64_t id);

  // Any thread; takes posted_mutex_. fn runs on the loop thread, in posting order.
  void post(std::function<void()> fn);

  // Loop thread: dispatches until stop().
  void run();
  void stop() { running_ = false; }  // loop thread
  // Before run(): called (loop thread) with an exception a handler, timer or posted function
  // threw, e.g. SQLite "database is locked" after its busy timeout. The loop carries on. Without
  // one, the exception leaves run().
  void set_error_handler(std::function<void(const std::exception&)> fn) { on_error_ = std::move(fn); }

 private:
  void drain_posted();
  int timeout_ms() const;
  void fire_timers();
  template <class F>
  void guarded(F&& f);
  std::function<void(const std::exception&)> on_error_;

  int epfd_ = -1;
  int wakefd_ = -1;
  bool running_ = false;
  std::unordered_map<int, std::shared_ptr<Handler>> handlers_;
  std::multimap<Clock::time_point, std::pair<std::uint64_t, std::function<void()>>> timers_;
  std::uint64_t next_timer_ = 1;
  std::mutex posted_mutex_;
  std::vector<std::function<void()>> posted_;  // guarded by posted_mutex_
};

}  // namespace omega::daemon
