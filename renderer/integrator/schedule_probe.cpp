#include "integrator/schedule_probe.h"

#include <algorithm>
#include <cstring>
#include <functional>
#include <numeric>
#include <queue>

namespace omega {

namespace {
// Seconds from `mark` to now, and `mark` moved to now: one clock reading ends one span and
// starts the next, so the spans add up to the recorded run exactly.
double lap(ScheduleProbe::Clock::time_point& mark) {
    const auto now = ScheduleProbe::Clock::now();
    const double s = std::chrono::duration<double>(now - mark).count();
    mark = now;
    return s;
}
}  // namespace

void ScheduleProbe::start() {
    regions_.clear();
    tasks_.clear();
    tail_s_ = total_s_ = 0;
    run_start_ = mark_ = Clock::now();
}

void ScheduleProbe::region_begin(const char* kind) {
    Region r;
    r.kind = kind;
    r.serial_before = lap(mark_);
    regions_.push_back(std::move(r));
    tasks_.clear();
    items_.clear();
}

void ScheduleProbe::region_end() {
    if (regions_.empty()) return;
    Region& r = regions_.back();
    const double wall = lap(mark_);
    const double busy = std::accumulate(tasks_.begin(), tasks_.end(), 0.0);
    r.overhead = std::max(0.0, wall - busy);
    r.tasks = std::move(tasks_);
    r.items = std::move(items_);
    tasks_.clear();
    items_.clear();
}

void ScheduleProbe::stop() {
    const auto now = Clock::now();
    tail_s_ = std::chrono::duration<double>(now - mark_).count();
    total_s_ = std::chrono::duration<double>(now - run_start_).count();
}

void ScheduleProbe::add_region(double serial_before, std::vector<double> tasks, const char* kind,
                               std::vector<uint32_t> items) {
    Region r;
    r.kind = kind;
    r.serial_before = serial_before;
    if (items.empty())
        for (uint32_t i = 0; i < tasks.size(); ++i) items.push_back(i);
    r.tasks = std::move(tasks);
    r.items = std::move(items);
    regions_.push_back(std::move(r));
}

size_t ScheduleProbe::tasks() const {
    size_t n = 0;
    for (const Region& r : regions_) n += r.tasks.size();
    return n;
}

ScheduleProbe::Prediction ScheduleProbe::predict(int workers, Order order) const {
    const int n = std::max(1, workers);
    Prediction p;
    p.serial_s = tail_s_;
    for (const Region& r : regions_) {
        p.serial_s += r.serial_before + r.overhead;
        // Each task to the worker that frees first, in the region's order.
        std::priority_queue<double, std::vector<double>, std::greater<>> free_at;
        for (int k = 0; k < n; ++k) free_at.push(0.0);
        double busy = 0, makespan = 0;
        std::vector<size_t> idx(r.tasks.size());
        std::iota(idx.begin(), idx.end(), size_t(0));
        if (order == Order::ByItem)
            std::stable_sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return r.items[a] < r.items[b]; });
        else if (order == Order::LongestFirst)
            std::stable_sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return r.tasks[a] > r.tasks[b]; });
        for (size_t j : idx) {
            const double t = r.tasks[j];
            const double start = free_at.top();
            free_at.pop();
            free_at.push(start + t);
            makespan = std::max(makespan, start + t);
            busy += t;
        }
        p.seconds += makespan;
        p.idle_s += makespan * n - busy;
        auto k = std::find_if(p.kinds.begin(), p.kinds.end(), [&](const Prediction::Kind& x) { return std::strcmp(x.kind, r.kind) == 0; });
        if (k == p.kinds.end()) k = p.kinds.insert(p.kinds.end(), {r.kind, 0.0, 0.0});
        k->seconds += makespan;
        k->idle_s += makespan * n - busy;
    }
    p.seconds += p.serial_s;
    return p;
}

}  // namespace omega
