#include "core/extract/brick_prefetcher.h"

#include <algorithm>

#include "core/thread_name.h"

namespace vdiso {

BrickPrefetcher::BrickPrefetcher(BrickSource& source, size_t lookahead, int readers)
    : mSource(source), mLookahead(lookahead) {
    if (mLookahead == 0) return;
    mBackground = source.loadsInBackground();
    if (mBackground) readers = std::min(readers, kBackgroundReaders);
    try {
        for (int k = 0; k < std::max(readers, 1); ++k)
            mThreads.emplace_back([this] {
                nameThisThread("vdiso-reader");
                mBackground ? runInBackground() : run();
            });
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
    return index;
}

size_t BrickPrefetcher::availableLocked() const {
    const size_t target = std::max(mNext, mConsumed + 1);
    const size_t limit = std::min(mPublished, mConsumed + 1 + mLookahead);
    return limit > target ? limit - target : 0;
}

void BrickPrefetcher::publish() {
    bool work;
    {
        std::lock_guard lock(mMutex);
        if (mPublished == mItems.size()) return;  // nothing new: no reader woken (called every brick)
        mPublished = mItems.size();
        work = availableLocked() > 0;
    }
    if (work) mChanged.notify_one();
}

void BrickPrefetcher::close() {
    {
        std::lock_guard lock(mMutex);
        mClosed = true;
        mPublished = mItems.size();
    }
    mChanged.notify_all();
}

void BrickPrefetcher::consumed(size_t i) {
    std::deque<std::pair<size_t, BrickHandle>> done;
    bool work, finished;
    {
        std::lock_guard lock(mMutex);
        mConsumed = std::max(mConsumed, i);
        if (i < mUsed.size()) mUsed[i] = 1;
        while (!mPinned.empty() && mPinned.front().first < mConsumed) {
            mSkippedLoaded += !mUsed[mPinned.front().first];
            done.push_back(std::move(mPinned.front()));
            mPinned.pop_front();
        }
        work = availableLocked() > 0;
        finished = mClosed && std::max(mNext, mConsumed + 1) >= mItems.size();
    }
    if (finished) mChanged.notify_all();  // nothing left to read: every reader ends
    else if (work) mChanged.notify_one();
}  // `done` releases its pins here, outside the lock

void BrickPrefetcher::cancel(size_t i) {
    std::lock_guard lock(mMutex);
    if (i < mItems.size()) mItems[i] = kCancelled;
}

void BrickPrefetcher::offer(std::vector<int64_t> ids) {
    std::lock_guard lock(mMutex);
    mOffered = std::move(ids);
}

size_t BrickPrefetcher::offeredLoaded() const {
    std::lock_guard lock(mMutex);
    return mOfferedLoaded;
}

size_t BrickPrefetcher::skippedLoaded() const {
    std::lock_guard lock(mMutex);
    return mSkippedLoaded;
}

BrickPrefetcher::Run BrickPrefetcher::takeRunLocked(size_t i) {
    // With it, the bricks it is read with (next to it in a store's file) found among the next
    // items: one read for them all, where the source can. A brick joins when it reads
    // together with one already in (BrickSource::readsTogether), so the run is a chain.
    Run run{{mItems[i], i}};
    auto joins = [&](int64_t id) {
        for (const auto& [brick, item] : run)
            if (id == brick) return false;
        for (const auto& [brick, item] : run)
            if (mSource.readsTogether(brick, id)) return true;
        return false;
    };
    const size_t end = std::min({mPublished, i + kRunWindow, mConsumed + 1 + mLookahead});
    for (bool grew = true; grew && run.size() < kMaxRun;) {
        grew = false;
        for (size_t j = i + 1; j < end && run.size() < kMaxRun; ++j) {
            if (mTaken[j] || mItems[j] == kCancelled) continue;
            if (joins(mItems[j])) {
                run.emplace_back(mItems[j], j);
                mTaken[j] = 1;
                grew = true;
            }
        }
    }
    // Then offered bricks that join it, not in memory already (one would make the source
    // read them one by one).
    for (bool grew = true; grew && run.size() < kMaxRun;) {
        grew = false;
        for (size_t k = 0; k < mOffered.size() && run.size() < kMaxRun; ++k)
            if (mOffered[k] != kCancelled && joins(mOffered[k]) && !mSource.isResident(mOffered[k])) {
                run.emplace_back(mOffered[k], kOfferedItem);
                mOffered[k] = kCancelled;  // read once
                grew = true;
            }
    }
    return run;
}

void BrickPrefetcher::keepLocked(const Run& run, std::vector<BrickHandle>& bricks) {
    for (size_t k = 0; k < run.size(); ++k) {
        const size_t item = run[k].second;
        if (!bricks[k].samples()) continue;  // held or loading already when a background load started
        if (item == kOfferedItem) {  // in the source now; its pin goes with `bricks`
            ++mOfferedLoaded;
            continue;
        }
        // The extraction may have got there meanwhile and acquired the brick itself; or it has
        // stopped.
        if (item < mConsumed || mStop) {
            mSkippedLoaded += !mUsed[item];
            continue;  // its pin goes with `bricks`
        }
        // Readers finish out of order: keep the pins sorted for consumed().
        auto at = mPinned.end();
        while (at != mPinned.begin() && std::prev(at)->first > item) --at;
        mPinned.emplace(at, item, std::move(bricks[k]));
    }
}

void BrickPrefetcher::run() {
    for (;;) {
        std::unique_lock lock(mMutex);
        // The item in use is the extraction's own to load; fetching one it has already passed
        // could only read it a second time.
        auto target = [&] { return std::max(mNext, mConsumed + 1); };
        mChanged.wait(lock, [&] {
            return mStop || (target() < mPublished && target() < mConsumed + 1 + mLookahead) ||
                   (mClosed && target() >= mItems.size());
        });
        if (mStop || target() >= mItems.size()) return;
        const size_t i = target();
        mNext = i + 1;
        // One reader woken at a time (a wake-up of every reader at each brick cost more CPU than
        // the requests over a network): this one hands what is left to the next.
        if (availableLocked() > 0) mChanged.notify_one();
        if (mItems[i] == kCancelled || mTaken[i]) continue;
        const Run run = takeRunLocked(i);
        lock.unlock();
        std::vector<BrickHandle> bricks;
        try {
            if (run.size() == 1) {
                bricks.push_back(mSource.acquire(run[0].first));
            } else {
                std::vector<int64_t> ids;
                for (const auto& [brick, item] : run) ids.push_back(brick);
                bricks = mSource.acquireTogether(ids);
            }
        } catch (...) {
            return;
        }
        lock.lock();
        keepLocked(run, bricks);
        lock.unlock();  // `bricks` releases the pins of those passed, outside the lock
    }
}

void BrickPrefetcher::loadReadyLocked(Load* load) {
    if (--load->waits > 0) return;
    mArrived.push_back(load);
    mChanged.notify_one();
}

void BrickPrefetcher::runInBackground() {
    // While the source wants more in flight than there are but this strip has nothing of its
    // own on the way to wake it, it looks again this often (another strip's load may end).
    constexpr auto kRoomCheck = std::chrono::milliseconds(5);
    auto target = [&] { return std::max(mNext, mConsumed + 1); };
    std::unique_lock lock(mMutex);
    for (;;) {
        if (!mArrived.empty()) {
            // Decoded first: the arrived run the extraction comes to first (it may be waiting).
            auto first = std::min_element(mArrived.begin(), mArrived.end(), [](const Load* a, const Load* b) {
                return a->run.front().second < b->run.front().second;
            });
            std::unique_ptr<Load> load(*first);
            mArrived.erase(first);
            lock.unlock();
            std::vector<BrickHandle> bricks;
            try {
                bricks = mSource.finishAcquire(*load->load);
            } catch (...) {
                // Left for the extraction's own acquire to meet and report.
            }
            lock.lock();
            --mLoading;
            if (!bricks.empty()) keepLocked(load->run, bricks);
            if (mStop && mLoading == 0) mChanged.notify_all();
            lock.unlock();  // `bricks` releases the pins of those passed, outside the lock
            bricks.clear();
            load.reset();
            lock.lock();
            continue;
        }
        const bool work = !mStop && target() < mPublished && target() < mConsumed + 1 + mLookahead;
        if (mLoading == 0 && (mStop || (!work && mClosed && target() >= mItems.size()))) {
            mChanged.notify_all();  // the other reader may be waiting for the last arrival
            return;
        }
        if (mStop) {
            // Loads on their way are waited for, but not longer than kStopPatience: a server
            // that stalls would otherwise hold the stop for its whole timeout.
            if (mChanged.wait_for(lock, kStopPatience) == std::cv_status::timeout) mCancelLoads = true;
            continue;
        }
        if (!work) {
            mChanged.wait(lock);
            continue;
        }
        if (mSource.loadsInFlight() >= mSource.loadsWanted()) {
            mChanged.wait_for(lock, kRoomCheck);
            continue;
        }
        const size_t i = target();
        mNext = i + 1;
        if (mItems[i] == kCancelled || mTaken[i]) continue;
        const Run run = takeRunLocked(i);
        lock.unlock();
        // (Never acquired here: a reader that waited on a brick loading would keep the loads
        // that arrived, that one's among them, from being finished.)
        startLoad(run);
        lock.lock();
    }
}

bool BrickPrefetcher::startLoad(const Run& run) {
    auto* load = new Load{run, nullptr, 2};
    std::vector<int64_t> ids;
    for (const auto& [brick, item] : run) ids.push_back(brick);
    {
        std::lock_guard lock(mMutex);
        ++mLoading;
    }
    std::unique_ptr<BrickLoad> started;
    try {
        started = mSource.startAcquire(ids, [this, load] {
            std::lock_guard hold(mMutex);
            loadReadyLocked(load);
        }, &mCancelLoads);
    } catch (...) {
        // Left for the extraction's own acquire to meet and report, as a failed read is.
    }
    std::lock_guard lock(mMutex);
    if (!started) {
        --mLoading;
        delete load;
        return false;
    }
    load->load = std::move(started);
    loadReadyLocked(load);
    return true;
}

}  // namespace vdiso
