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
            mTaken.push_back(0);
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
        mNext = i + 1;
        if (mItems[i] == kCancelled || mTaken[i]) continue;
        // With it, the bricks it is read with (x-neighbours in a store's file) found among the
        // next items: one read for the run, where the source can.
        std::vector<std::pair<int64_t, size_t>> run{{mItems[i], i}};  // brick, item
        const size_t end = std::min({mItems.size(), i + kRunWindow, mConsumed + 1 + mLookahead});
        for (bool grew = true; grew && run.size() < kMaxRun;) {
            grew = false;
            const int64_t lo = run.front().first, hi = run.back().first;
            for (size_t j = i + 1; j < end && !grew; ++j) {
                if (mTaken[j] || mItems[j] == kCancelled) continue;
                if (mItems[j] == hi + 1 && mSource.readsWithNext(hi)) {
                    run.emplace_back(mItems[j], j);
                    grew = true;
                } else if (mItems[j] == lo - 1 && mSource.readsWithNext(lo - 1)) {
                    run.emplace(run.begin(), mItems[j], j);
                    grew = true;
                }
                if (grew) mTaken[j] = 1;
            }
        }
        lock.unlock();
        std::vector<BrickHandle> bricks;
        try {
            if (run.size() == 1) bricks.push_back(mSource.acquire(run[0].first));
            else bricks = mSource.acquireRun(run.front().first, int(run.size()));
        } catch (...) {
            return;
        }
        lock.lock();
        for (size_t k = 0; k < run.size(); ++k) {
            const size_t item = run[k].second;
            // The extraction may have got there meanwhile and acquired the brick itself.
            if (item < mConsumed) {
                mSkippedLoaded += !mUsed[item];
                continue;  // its pin goes with `bricks`
            }
            // Readers finish out of order: keep the pins sorted for consumed().
            auto at = mPinned.end();
            while (at != mPinned.begin() && std::prev(at)->first > item) --at;
            mPinned.emplace(at, item, std::move(bricks[k]));
        }
        lock.unlock();  // `bricks` releases the pins of those passed, outside the lock
    }
}

}  // namespace vdiso
