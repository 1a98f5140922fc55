// The server's extraction workers: a fixed number of threads that run every viewer's frames,
// one pass (a VIEW's coarse or final frame) at a time, so the threads do not grow with the
// viewers. A task is queued at most once: a newer VIEW replaces the pending one inside the
// task, so a superseded frame never runs at all.
//
// Fair by viewer, not by pass: each task is charged the seconds its passes run, and the next
// pass is the due one of the task charged least (within kSlice, the one posted first; a first
// pass, someone joining or turning the volume, counts kFirstPassCredit less). A task idle for a
// while comes back at most kIdleCredit behind the least charged, so a viewer that sends VIEWs
// without end takes its share of the workers and no more: N such viewers cannot keep another
// from its frames, whatever they send.
//
// A first pass need not wait for a long later one to end: a later pass calls
// runFirstPassesHere(itself) between its bricks, which runs the waiting first passes of tasks charged
// less than it on its own thread, nested, while its other strips go on (at most one nested pass
// a worker at once). Someone joining a busy server sees the volume within a coarse pass's time.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <vector>

namespace vdiso::serve {

class FramePool {
public:
    using Clock = std::chrono::steady_clock;

    // Something with passes to run: a viewer's session.
    class Task {
    public:
        virtual ~Task() = default;
        // Runs one pass on a worker; may post() itself again for the next.
        virtual void runPass() = 0;
    };

    // Starts `workers` threads; throws std::system_error when they cannot be started.
    explicit FramePool(int workers);
    // Waits for the running passes and stops the workers; queued passes do not run.
    ~FramePool();
    FramePool(const FramePool&) = delete;
    FramePool& operator=(const FramePool&) = delete;

    // Queues a pass of `task` (not before `notBefore`) unless one is queued; while its pass runs,
    // the next is queued when it ends. `first`: the pass goes ahead of every later one. A first
    // pass posted for a task already queued for a later one moves it ahead.
    void post(Task& task, bool first, Clock::time_point notBefore = {});
    // Takes `task` out of the queue; a running pass goes on (join() waits for it). Later posts
    // are ignored.
    void remove(Task& task);
    // Waits while a pass of `task` runs; after remove(), the pool forgets the task.
    void join(Task& task);
    // No pass of `task` runs or is queued.
    bool idle(Task& task);

    // Whether a first pass waits (cheap: for a later pass to ask between its bricks).
    bool firstPassWaits() const { return mFirstWaiting.load(std::memory_order_relaxed) > 0; }
    // From a pass of `host` (any of its strips' threads): runs due first passes of tasks charged
    // less than `host` so far on this thread, one after another, while any waits and fewer than
    // workers() run so; returns how many ran. Their time is charged to them, not to `host`.
    int runFirstPassesHere(Task& host);

    // The fairness rule's constants, in seconds of passes run (see the top of this file).
    static constexpr double kSlice = 0.02, kFirstPassCredit = 0.05, kIdleCredit = 0.15;
    // Seconds of passes `task` was charged so far.
    double charged(Task& task);
    // Whether this thread is running a nested first pass (it then uses no threads of its own).
    static bool nested();

    int workers() const { return int(mThreads.size()); }
    uint64_t passes() const;  // passes begun so far
    size_t waiting() const;   // passes queued now

private:
    struct State {
        bool queued = false, running = false, removed = false;
        bool again = false, againFirst = false;  // posted while running
        Clock::time_point againNotBefore;
        double charged = 0;  // seconds its passes ran (nested passes charged to their own task)
        Clock::time_point runningSince;
        double nestedSeconds = 0;  // of other tasks' passes nested in its running one
    };
    struct Entry {
        Task* task;
        Clock::time_point notBefore;
        bool first;
        uint64_t order;  // when posted (a first pass posted over a later one: then)
    };
    void work();
    void enqueueLocked(Task& task, State& state, bool first, Clock::time_point notBefore);
    // The due entry the fairness rule picks (only first passes of tasks charged less than
    // `below`, if `firstOnly`), taken out of the queue and marked running; else nullptr and the
    // soonest time one becomes due.
    Task* takeDueLocked(bool firstOnly, double below, Clock::time_point& soonest);
    // Runs `task`'s pass (the lock released meanwhile), charges it, and queues its next one if
    // posted. Returns the seconds it ran.
    double runLocked(Task* task, std::unique_lock<std::mutex>& lock);
    void countFirstLocked();

    mutable std::mutex mMutex;
    std::condition_variable mChanged;  // a pass queued or ended, or stopping
    std::vector<Entry> mQueue;
    uint64_t mOrder = 0;
    double mLeastCharged = 0;  // the charge of the last task taken, never going back
    std::atomic<size_t> mFirstWaiting{0};  // first passes queued, read without the lock
    int mNested = 0;                       // nested first passes running
    std::unordered_map<Task*, State> mStates;
    uint64_t mPasses = 0;
    bool mStopping = false;
    std::vector<std::thread> mThreads;
};

}  // namespace vdiso::serve
