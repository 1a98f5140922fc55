#include "serve/frame_pool.h"

#include <algorithm>
#include <limits>

#include "core/thread_name.h"

namespace vdiso::serve {

FramePool::FramePool(int workers) {
    try {
        for (int k = 0; k < std::max(1, workers); ++k) mThreads.emplace_back([this] { work(); });
    } catch (...) {
        {
            std::lock_guard lock(mMutex);
            mStopping = true;
        }
        mChanged.notify_all();
        for (std::thread& t : mThreads) t.join();
        throw;
    }
}

FramePool::~FramePool() {
    {
        std::lock_guard lock(mMutex);
        mStopping = true;
    }
    mChanged.notify_all();
    for (std::thread& t : mThreads) t.join();
}

void FramePool::countFirstLocked() {
    mFirstWaiting = size_t(std::count_if(mQueue.begin(), mQueue.end(), [](const Entry& e) { return e.first; }));
}

void FramePool::enqueueLocked(Task& task, State& state, bool first, Clock::time_point notBefore) {
    if (state.queued) {
        if (!first) return;
        const auto queued = std::find_if(mQueue.begin(), mQueue.end(), [&](const Entry& e) { return e.task == &task; });
        if (queued == mQueue.end() || queued->first) return;  // queued first already
        queued->first = true;
        queued->order = mOrder++;
        countFirstLocked();
        return;
    }
    // Back from idle: at most kIdleCredit behind the least charged (it cannot bank its idle time).
    if (!state.running) state.charged = std::max(state.charged, mLeastCharged - kIdleCredit);
    mQueue.push_back({&task, notBefore, first, mOrder++});
    countFirstLocked();
    state.queued = true;
}

void FramePool::post(Task& task, bool first, Clock::time_point notBefore) {
    {
        std::lock_guard lock(mMutex);
        State& state = mStates[&task];
        if (state.removed) return;
        if (state.running) {
            state.againFirst = state.again ? state.againFirst || first : first;
            state.again = true;
            state.againNotBefore = std::max(state.againNotBefore, notBefore);
            return;
        }
        enqueueLocked(task, state, first, notBefore);
    }
    mChanged.notify_all();
}

void FramePool::remove(Task& task) {
    std::lock_guard lock(mMutex);
    State& state = mStates[&task];
    state.removed = true;
    state.again = false;
    if (!state.queued) return;
    std::erase_if(mQueue, [&](const Entry& e) { return e.task == &task; });
    countFirstLocked();
    state.queued = false;
}

void FramePool::join(Task& task) {
    std::unique_lock lock(mMutex);
    mChanged.wait(lock, [&] {
        const auto found = mStates.find(&task);
        return found == mStates.end() || !found->second.running;
    });
    const auto found = mStates.find(&task);
    if (found != mStates.end() && found->second.removed) mStates.erase(found);
}

bool FramePool::idle(Task& task) {
    std::lock_guard lock(mMutex);
    const auto found = mStates.find(&task);
    return found == mStates.end() || (!found->second.running && !found->second.queued);
}

uint64_t FramePool::passes() const {
    std::lock_guard lock(mMutex);
    return mPasses;
}

size_t FramePool::waiting() const {
    std::lock_guard lock(mMutex);
    return mQueue.size();
}

double FramePool::charged(Task& task) {
    std::lock_guard lock(mMutex);
    const auto found = mStates.find(&task);
    return found == mStates.end() ? 0.0 : found->second.charged;
}

namespace {
thread_local bool tNested = false;
}  // namespace

bool FramePool::nested() { return tNested; }

FramePool::Task* FramePool::takeDueLocked(bool firstOnly, double below, Clock::time_point& soonest) {
    const Clock::time_point now = Clock::now();
    soonest = Clock::time_point::max();
    auto key = [&](const Entry& e) { return mStates[e.task].charged - (e.first ? kFirstPassCredit : 0.0); };
    double least = std::numeric_limits<double>::infinity();
    for (const Entry& e : mQueue) {
        if (firstOnly && !e.first) continue;
        if (e.notBefore > now) {
            soonest = std::min(soonest, e.notBefore);
            continue;
        }
        least = std::min(least, key(e));
    }
    if (least == std::numeric_limits<double>::infinity() || (firstOnly && least + kSlice >= below)) return nullptr;
    // Within a slice of the least charged, in the order posted: tasks alike take turns.
    auto pick = mQueue.end();
    for (auto e = mQueue.begin(); e != mQueue.end(); ++e)
        if ((!firstOnly || e->first) && e->notBefore <= now && key(*e) <= least + kSlice &&
            (pick == mQueue.end() || e->order < pick->order))
            pick = e;
    Task* task = pick->task;
    mQueue.erase(pick);
    countFirstLocked();
    State& state = mStates[task];
    state.queued = false;
    state.running = true;
    state.runningSince = now;
    mLeastCharged = std::max(mLeastCharged, state.charged);
    ++mPasses;
    return task;
}

double FramePool::runLocked(Task* task, std::unique_lock<std::mutex>& lock) {
    const Clock::time_point start = Clock::now();
    mStates[task].nestedSeconds = 0;
    lock.unlock();
    try {
        task->runPass();
    } catch (...) {  // a task answers its own errors; none may end a worker
    }
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    lock.lock();
    State& after = mStates[task];
    after.running = false;
    // Nested passes ran on this pass's time but are charged to their own tasks.
    after.charged += std::max(0.0, seconds - after.nestedSeconds);
    if (after.again && !after.removed) {
        after.again = false;
        enqueueLocked(*task, after, after.againFirst, after.againNotBefore);
    }
    mChanged.notify_all();
    return seconds;
}

int FramePool::runFirstPassesHere(Task& host) {
    if (tNested) return 0;
    std::unique_lock lock(mMutex);
    int ran = 0;
    while (!mStopping && mNested < workers()) {
        // Only tasks charged less than the host so far: a busy viewer's passes do not take
        // another's time this way.
        State& running = mStates[&host];
        const double hostCharged = running.charged - running.nestedSeconds +
                                   std::chrono::duration<double>(Clock::now() - running.runningSince).count();
        Clock::time_point soonest;
        Task* task = takeDueLocked(true, hostCharged, soonest);
        if (!task) break;
        ++mNested;
        tNested = true;
        const double seconds = runLocked(task, lock);
        mStates[&host].nestedSeconds += seconds;
        tNested = false;
        --mNested;
        ++ran;
    }
    return ran;
}

void FramePool::work() {
    nameThisThread("vdiso-frame");
    std::unique_lock lock(mMutex);
    while (!mStopping) {
        // The due entry the fairness rule picks; else wait for the soonest one not yet due.
        Clock::time_point soonest;
        Task* task = takeDueLocked(false, 0, soonest);
        if (!task) {
            if (soonest == Clock::time_point::max())
                mChanged.wait(lock);
            else
                mChanged.wait_until(lock, soonest);
            continue;
        }
        runLocked(task, lock);
    }
}

}  // namespace vdiso::serve
