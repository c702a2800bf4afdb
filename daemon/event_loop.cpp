#include "daemon/event_loop.h"

#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <system_error>

namespace omega::daemon {

namespace {
[[noreturn]] void throw_errno(const char* what) { throw std::system_error(errno, std::generic_category(), what); }
}  // namespace

EventLoop::EventLoop() {
  epfd_ = epoll_create1(EPOLL_CLOEXEC);
  if (epfd_ < 0) throw_errno("epoll_create1");
  wakefd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wakefd_ < 0) throw_errno("eventfd");
  add(wakefd_, EPOLLIN, [this](std::uint32_t) {
    std::uint64_t n;
    while (read(wakefd_, &n, sizeof n) > 0) {
    }
    drain_posted();
  });
}

EventLoop::~EventLoop() {
  if (wakefd_ >= 0) close(wakefd_);
  if (epfd_ >= 0) close(epfd_);
}

void EventLoop::add(int fd, std::uint32_t events, Handler h) {
  epoll_event ev{};
  ev.events = events;
  ev.data.fd = fd;
  if (epoll_ctl(epfd_, EPOLL_CTL_ADD, fd, &ev) < 0) throw_errno("epoll_ctl(ADD)");
  handlers_[fd] = std::make_shared<Handler>(std::move(h));
}

void EventLoop::modify(int fd, std::uint32_t events) {
  epoll_event ev{};
  ev.events = events;
  ev.data.fd = fd;
  if (epoll_ctl(epfd_, EPOLL_CTL_MOD, fd, &ev) < 0) throw_errno("epoll_ctl(MOD)");
}

void EventLoop::remove(int fd) {
  epoll_ctl(epfd_, EPOLL_CTL_DEL, fd, nullptr);
  handlers_.erase(fd);
}

std::uint64_t EventLoop::add_timer(double seconds, std::function<void()> fn) {
  auto when = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  std::uint64_t id = next_timer_++;
  timers_.emplace(when, std::make_pair(id, std::move(fn)));
  return id;
}

void EventLoop::cancel_timer(std::uint64_t id) {
  for (auto it = timers_.begin(); it != timers_.end(); ++it)
    if (it->second.first == id) {
      timers_.erase(it);
      return;
    }
}

void EventLoop::post(std::function<void()> fn) {
  {
    std::lock_guard lock(posted_mutex_);
    posted_.push_back(std::move(fn));
  }
  std::uint64_t one = 1;
  ssize_t r = write(wakefd_, &one, sizeof one);
  (void)r;  // EAGAIN only when the counter is saturated: the loop is awake anyway
}

template <class F>
void EventLoop::guarded(F&& f) {
  if (!on_error_) return f();
  try {
    f();
  } catch (const std::exception& e) {
    on_error_(e);
  }
}

void EventLoop::drain_posted() {
  std::vector<std::function<void()>> batch;
  {
    std::lock_guard lock(posted_mutex_);
    batch.swap(posted_);
  }
  for (auto& fn : batch) guarded(fn);
}

int EventLoop::timeout_ms() const {
  if (timers_.empty()) return -1;
  auto d = timers_.begin()->first - Clock::now();
  auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(d).count() + 1;
  return ms < 0 ? 0 : static_cast<int>(std::min<long long>(ms, 60000));
}

void EventLoop::fire_timers() {
  auto now = Clock::now();
  while (!timers_.empty() && timers_.begin()->first <= now) {
    auto fn = std::move(timers_.begin()->second.second);
    timers_.erase(timers_.begin());
    guarded(fn);
  }
}

void EventLoop::run() {
  running_ = true;
  epoll_event events[64];
  while (running_) {
    int n = epoll_wait(epfd_, events, 64, timeout_ms());
    if (n < 0) {
      if (errno == EINTR) continue;
      throw_errno("epoll_wait");
    }
    for (int i = 0; i < n && running_; ++i) {
      auto it = handlers_.find(events[i].data.fd);
      if (it == handlers_.end()) continue;  // removed by an earlier handler in this batch
      std::shared_ptr<Handler> h = it->second;  // keeps it alive if it removes itself
      guarded([&] { (*h)(events[i].events); });
    }
    fire_timers();
  }
  drain_posted();
}

}  // namespace omega::daemon
