#include "serve/frame_pool.h"

#include <algorithm>

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

void FramePool::enqueueLocked(Task& task, State& state, bool first, Clock::time_point notBefore) {
    if (state.queued) {
        if (!first) return;
        const auto later = std::find_if(mLater.begin(), mLater.end(), [&](const Entry& e) { return e.task == &task; });
        if (later == mLater.end()) return;  // queued first already
        mFirst.push_back(*later);
        mLater.erase(later);
        mFirstWaiting = mFirst.size();
        return;
    }
    (first ? mFirst : mLater).push_back({&task, notBefore});
    mFirstWaiting = mFirst.size();
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
    for (std::deque<Entry>* queue : {&mFirst, &mLater})
        std::erase_if(*queue, [&](const Entry& e) { return e.task == &task; });
    mFirstWaiting = mFirst.size();
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
    return mFirst.size() + mLater.size();
}

namespace {
thread_local bool tNested = false;
}  // namespace

bool FramePool::nested() { return tNested; }

FramePool::Task* FramePool::takeDueLocked(bool firstOnly, Clock::time_point& soonest) {
    const Clock::time_point now = Clock::now();
    soonest = Clock::time_point::max();
    for (std::deque<Entry>* queue : {&mFirst, &mLater}) {
        if (firstOnly && queue == &mLater) break;
        for (auto e = queue->begin(); e != queue->end(); ++e) {
            if (e->notBefore <= now) {
                Task* task = e->task;
                queue->erase(e);
                mFirstWaiting = mFirst.size();
                State& state = mStates[task];
                state.queued = false;
                state.running = true;
                ++mPasses;
                return task;
            }
            soonest = std::min(soonest, e->notBefore);
        }
    }
    return nullptr;
}

void FramePool::runLocked(Task* task, std::unique_lock<std::mutex>& lock) {
    lock.unlock();
    try {
        task->runPass();
    } catch (...) {  // a task answers its own errors; none may end a worker
    }
    lock.lock();
    State& after = mStates[task];
    after.running = false;
    if (after.again && !after.removed) {
        after.again = false;
        enqueueLocked(*task, after, after.againFirst, after.againNotBefore);
    }
    mChanged.notify_all();
}

int FramePool::runFirstPassesHere() {
    if (tNested) return 0;
    std::unique_lock lock(mMutex);
    int ran = 0;
    while (!mStopping && mNested < workers()) {
        Clock::time_point soonest;
        Task* task = takeDueLocked(true, soonest);
        if (!task) break;
        ++mNested;
        tNested = true;
        runLocked(task, lock);
        tNested = false;
        --mNested;
        ++ran;
    }
    return ran;
}

void FramePool::work() {
    std::unique_lock lock(mMutex);
    while (!mStopping) {
        // The first due entry, first passes before later ones; else the soonest one not yet due.
        Clock::time_point soonest;
        Task* task = takeDueLocked(false, soonest);
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
