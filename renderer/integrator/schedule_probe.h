#pragma once
// How a render's work divides into parallel tasks, recorded on one thread, to predict its speedup
// on more cores than the machine at hand (bench/throughput; issue 12 asks for 1 -> 16 threads).
//
// A RenderSession running on ONE thread reports each parallel region (a pass's tiles, a batch's
// splat bands, a pass's error sums) and the duration of each of its tasks; the time outside
// regions, and inside them but outside tasks (spawning, the driver's own work), is serial.
// predict(N) replays the record on N workers: a region takes the makespan of its tasks handed out
// in order, each to the worker that frees first (TBB's dynamic scheduling, idealised), and ends at
// a barrier; serial time stays as it was. What the model leaves out is everything threads share in
// hardware (memory bandwidth, caches, SMT siblings, clock boost), so its speedup is an upper bound:
// a measured speedup below it points at the hardware, one at it at the schedule (barriers,
// imbalance, serial parts).
//
// Concurrency: every call comes from the session's one worker or its driver thread, never two
// at once (a one-thread arena runs tasks on the calling thread).
#include <chrono>
#include <cstdint>
#include <vector>

namespace omega {

class ScheduleProbe {
public:
    using Clock = std::chrono::steady_clock;

    // A recorded session cuts its work as a run on this many workers would (SplatBands::relayout
    // splits heavy bands per worker count): the largest count the bench predicts.
    static constexpr int kLayoutWorkers = 16;

    // The recorded run starts now / ended now (the caller brackets RenderSession::run()).
    void start();
    void stop();
    // A parallel region begins and ends (the driver thread, around arena.execute). `kind` names
    // what its tasks are (a string literal: "tiles", "bands", "merge"), for predict()'s breakdown.
    void region_begin(const char* kind);
    void region_end();
    // One task of the open region, work item `item` (a tile or band index), took `seconds`.
    void task(double seconds, uint32_t item) {
        tasks_.push_back(seconds);
        items_.push_back(item);
    }

    // Times one task of the open region from construction to destruction; a null probe: nothing.
    class TaskTimer {
    public:
        TaskTimer(ScheduleProbe* p, uint32_t item) : p_(p), item_(item) {
            if (p_) t0_ = Clock::now();
        }
        ~TaskTimer() {
            if (p_) p_->task(std::chrono::duration<double>(Clock::now() - t0_).count(), item_);
        }
        TaskTimer(const TaskTimer&) = delete;
        TaskTimer& operator=(const TaskTimer&) = delete;

    private:
        ScheduleProbe* p_;
        uint32_t item_;
        Clock::time_point t0_{};
    };

    struct Prediction {
        double seconds = 0;     // wall time on N workers
        double serial_s = 0;    // of which outside any task (the same for every N)
        double idle_s = 0;      // worker-seconds waiting at region barriers
        // Per region kind, in order of first appearance: {kind, seconds on N workers, idle worker-seconds}.
        struct Kind {
            const char* kind;
            double seconds, idle_s;
        };
        std::vector<Kind> kinds;
    };
    // The order each region's tasks are handed out in: as they ran, by item index (tiles top to
    // bottom, what tbb::parallel_for's ranges start from), or longest first (what ordering by a
    // known cost could reach).
    enum class Order { AsRun, ByItem, LongestFirst };
    Prediction predict(int workers, Order order = Order::AsRun) const;

    double recorded_seconds() const { return total_s_; }  // start() to stop()
    size_t regions() const { return regions_.size(); }
    size_t tasks() const;

    // Synthetic records (tests): a region of these task durations after `serial_before` seconds
    // of serial work, and serial work after the last region.
    // Items default to 0, 1, 2, ... (the tasks' order).
    void add_region(double serial_before, std::vector<double> tasks, const char* kind = "tasks",
                    std::vector<uint32_t> items = {});
    void set_tail(double serial_after) { tail_s_ = serial_after; }

private:
    struct Region {
        const char* kind = "";
        double serial_before = 0;  // since the last region ended (or the run started)
        double overhead = 0;       // inside the region, outside its tasks (serial)
        std::vector<double> tasks;
        std::vector<uint32_t> items;  // each task's work item
    };
    std::vector<Region> regions_;
    std::vector<double> tasks_;    // the open region's
    std::vector<uint32_t> items_;
    Clock::time_point run_start_{}, mark_{};
    double tail_s_ = 0, total_s_ = 0;
};

}  // namespace omega
