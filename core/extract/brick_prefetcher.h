// Loads bricks into a BrickSource ahead of an extraction, on reader threads of its own, so
// that reading and decoding overlap extraction (docs/design.md, "Memory and reads"). Several readers
// keep several reads queued at the device: a brick is a small random read, and one at a time
// a disk's latency, not its bandwidth, sets the pace (a read waits on the device, not on a
// core, so readers beyond the cores cost nothing while they wait).
//
// The extraction pushes the bricks it has decided to visit, in the order it will use them
// (all at once for the full methods; as its look-ahead finds them for SAGE), and says which
// one it is about to use. The prefetcher loads only pushed bricks, in order, never more than
// `lookahead` beyond the one in use, and keeps each pinned until the extraction has moved past
// it: a prefetched brick is not evicted before its use, so none is read twice. The brick in
// use the extraction acquires itself (a cache hit when the prefetcher got there first). The
// source must hold more than `lookahead` bricks; if it fills with pins, prefetching stops.
// push/close/consumed are for one extraction thread; a failed load is left for the
// extraction's own acquire to meet and report.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "core/brick_source.h"

namespace vdiso {

class BrickPrefetcher {
public:
    // lookahead 0: no thread; every call does nothing. Items are taken in list order by
    // `readers` threads, each loading one brick at a time, or with it the bricks among the next
    // items that the source reads with it (BrickSource::readsTogether: next to it in a store's
    // file), in one read.
    //
    // From a source that loads in the background (BrickSource::loadsInBackground: a store at a
    // URL) a reader does not wait on its read: it starts loads while the source wants more in
    // flight (loadsWanted over loadsInFlight, every reader of the source counted) and decodes
    // those that have arrived (finishAcquire), so the requests in flight follow the link, not
    // the threads; then at most kBackgroundReaders threads, whatever `readers` says.
    BrickPrefetcher(BrickSource& source, size_t lookahead, int readers = kDefaultReaders);
    static constexpr int kDefaultReaders = 2, kBackgroundReaders = 2;
    ~BrickPrefetcher();
    BrickPrefetcher(const BrickPrefetcher&) = delete;
    BrickPrefetcher& operator=(const BrickPrefetcher&) = delete;

    // Appends brick `id` to the list; returns its index in it. Readers take it once it is
    // published: the bricks pushed between two publish() calls are gathered into runs among
    // themselves before any is read (a reader woken at the first push would read it alone).
    size_t push(int64_t id);
    void publish();
    // Bricks likely wanted soon but not pushed (found ahead, not yet known to show): a reader
    // reads those the source reads together with its run in the same request, into the source
    // (its cache), unpinned. Replaces the last offer. Where a request waits a round trip, the
    // neighbours in the file come with it instead of in a request of their own.
    void offer(std::vector<int64_t> ids);
    // No more pushes (what was pushed is published): the thread ends once it has loaded what
    // is left.
    void close();
    // The extraction is about to use item i (it acquires that brick itself): the pins of
    // earlier items are released, whether they were used or skipped.
    void consumed(size_t i);
    // Item i is no longer wanted: it is not loaded if the thread has not got to it yet.
    void cancel(size_t i);
    // Ends the thread at once (loading nothing more) and releases every pin; for an
    // extraction that has finished early or that will use nothing more it pushed. Loads in the
    // background already on their way are waited for and kept in the source (a server's next
    // frame, from a nearby camera, likely wants them): about a round trip, at most a second
    // (then they are ended).
    void stop();

    // Items loaded by the thread and released unused (skipped by consumed, or left at stop).
    size_t skippedLoaded() const;
    // Offered bricks read along with a run.
    size_t offeredLoaded() const;

private:
    // A run of bricks read together: (brick, item) pairs, the item kOfferedItem for an offered one.
    using Run = std::vector<std::pair<int64_t, size_t>>;
    // A run on its way from a source that loads in the background; `waits` counts down its
    // arrival and its load's being stored here, either first.
    struct Load {
        Run run;
        std::unique_ptr<BrickLoad> load;
        int waits = 2;
    };
    void run();
    void runInBackground();
    // Under the lock: item i's run (it, then the bricks read with it among the next items, then
    // offered ones), marked taken.
    Run takeRunLocked(size_t i);
    // Under the lock: the run's bricks pinned for their items; what is left in `bricks` (bricks
    // passed meanwhile, offered ones) the caller releases outside the lock.
    void keepLocked(const Run& run, std::vector<BrickHandle>& bricks);
    // A load's arrival or its storing: the second puts it on mArrived.
    void loadReadyLocked(Load* load);
    // Starts loading the run's bricks not held or loading already (BrickSource::startAcquire);
    // false, nothing started, where every one is or the start failed.
    bool startLoad(const Run& run);
    // Under the lock: items a reader could take now (within the published list and the
    // look-ahead). Work that appears wakes one reader, which wakes the next while more is left.
    size_t availableLocked() const;

    BrickSource& mSource;
    size_t mLookahead;
    std::vector<int64_t> mItems;  // brick ids; kCancelled for cancelled items
    static constexpr int64_t kCancelled = -1;
    static constexpr size_t kOfferedItem = SIZE_MAX;  // a run's offered brick: no item
    // A run of bricks read together (BrickSource::acquireTogether) gathers them from the next
    // kRunWindow items, at most kMaxRun.
    static constexpr size_t kRunWindow = 32, kMaxRun = 8;
    std::vector<uint8_t> mUsed;   // consumed() named it
    std::vector<uint8_t> mTaken;  // read with an earlier item's brick, in one run
    size_t mConsumed = 0;
    size_t mNext = 0;             // the next item a reader takes
    size_t mPublished = 0;        // items readers may take: [0, mPublished)
    bool mClosed = false, mStop = false;
    size_t mSkippedLoaded = 0;
    std::vector<int64_t> mOffered;
    size_t mOfferedLoaded = 0;
    std::deque<std::pair<size_t, BrickHandle>> mPinned;  // by item index, ascending
    mutable std::mutex mMutex;
    std::condition_variable mChanged;
    std::vector<std::thread> mThreads;
    // Loading in the background.
    bool mBackground = false;
    size_t mLoading = 0;            // loads started, not yet finished
    std::atomic<bool> mCancelLoads{false};  // the loads in flight end (a stop waited too long)
    static constexpr std::chrono::milliseconds kStopPatience{1000};
    std::vector<Load*> mArrived;    // arrived and stored, to finish (owned)
};

}  // namespace vdiso
