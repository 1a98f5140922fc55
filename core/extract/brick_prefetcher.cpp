#include "core/extract/brick_prefetcher.h"

#include <algorithm>

namespace vdiso {

BrickPrefetcher::BrickPrefetcher(BrickSource& source, size_t lookahead, int readers)
    : mSource(source), mLookahead(lookahead) {
    if (mLookahead == 0) return;
    try {
        for (int k = 0; k < std::max(readers, 1); ++k) mThreads.emplace_back([this] { run(); });
    } catch (...) {
        stop();  // the threads already started, joined: no destructor runs after a throw
        throw;
    }
}

BrickPrefetcher::~BrickPrefetcher() { stop(); }

void BrickPrefetcher::stop() {
    {
        std::lock_guard lock(mMutex);
        mStop = true;
    }
    mChanged.notify_all();
    for (std::thread& t : mThreads)
        if (t.joinable()) t.join();
    for (const auto& [item, brick] : mPinned) mSkippedLoaded += !mUsed[item];
    mPinned.clear();
}

size_t BrickPrefetcher::push(int64_t id) {
    size_t index;
    {
        std::lock_guard lock(mMutex);
        index = mItems.size();
        if (mLookahead > 0) {
            mItems.push_back(id);
            mUsed.push_back(0);
        }
    }
    mChanged.notify_all();
    return index;
}

void BrickPrefetcher::close() {
    {
        std::lock_guard lock(mMutex);
        mClosed = true;
    }
    mChanged.notify_all();
}

void BrickPrefetcher::consumed(size_t i) {
    std::deque<std::pair<size_t, BrickHandle>> done;
    {
        std::lock_guard lock(mMutex);
        mConsumed = std::max(mConsumed, i);
        if (i < mUsed.size()) mUsed[i] = 1;
        while (!mPinned.empty() && mPinned.front().first < mConsumed) {
            mSkippedLoaded += !mUsed[mPinned.front().first];
            done.push_back(std::move(mPinned.front()));
            mPinned.pop_front();
        }
    }
    mChanged.notify_all();
}  // `done` releases its pins here, outside the lock

void BrickPrefetcher::cancel(size_t i) {
    std::lock_guard lock(mMutex);
    if (i < mItems.size()) mItems[i] = kCancelled;
}

size_t BrickPrefetcher::skippedLoaded() const {
    std::lock_guard lock(mMutex);
    return mSkippedLoaded;
}

void BrickPrefetcher::run() {
    for (;;) {
        std::unique_lock lock(mMutex);
        // The item in use is the extraction's own to load; fetching one it has already passed
        // could only read it a second time.
        auto target = [&] { return std::max(mNext, mConsumed + 1); };
        mChanged.wait(lock, [&] {
            return mStop || (target() < mItems.size() && target() < mConsumed + 1 + mLookahead) ||
                   (mClosed && target() >= mItems.size());
        });
        if (mStop || target() >= mItems.size()) return;
        const size_t i = target();
        const int64_t id = mItems[i];
        mNext = i + 1;
        if (id == kCancelled) continue;
        lock.unlock();
        BrickHandle brick;
        try {
            brick = mSource.acquire(id);
        } catch (...) {
            return;
        }
        lock.lock();
        // The extraction may have got there meanwhile and acquired the brick itself.
        if (i < mConsumed) {
            mSkippedLoaded += !mUsed[i];
            lock.unlock();
            continue;  // `brick` releases its pin
        }
        // Readers finish out of order: keep the pins sorted for consumed().
        auto at = mPinned.end();
        while (at != mPinned.begin() && std::prev(at)->first > i) --at;
        mPinned.emplace(at, i, std::move(brick));
    }
}

}  // namespace vdiso
