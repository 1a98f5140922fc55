// The brick cache: BrickSource over a store reader, holding decoded bricks in an LRU under a
// byte budget.
//
// acquire() returns a brick pinned until its handle is released; pinned bricks are never
// evicted. The cache never holds more decoded bytes than the budget: if every slot is pinned
// when another brick is needed, acquire() throws (the budget is too small for the caller's
// working set). Counters record requests, hits, misses, evictions, bytes read from disk and
// the seconds spent reading and decoding (summed over threads). Thread-safe: acquire/release
// take a lock once per brick, never per cell; reading and decoding happen outside it, so
// threads load different bricks in parallel, and a thread asking for a brick another is
// loading waits for it instead of reading it twice.
#pragma once

#include <atomic>
#include <cstdint>
#include <list>
#include <memory>
#include <condition_variable>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "core/brick_source.h"
#include "io/store/brick_store.h"

namespace vdiso {

struct CacheCounters {
    uint64_t requests = 0, hits = 0, misses = 0, evictions = 0;
    uint64_t bytesRead = 0;      // stored (compressed) bytes read from the file
    double readSeconds = 0;      // in pread
    double decodeSeconds = 0;    // checksum, decompression, unshuffle
};

// The cache's budget does not fit what is asked of it (too little for the bricks pinned at
// once, or more than the machine gives). Front ends name their own setting for the budget
// (--cache-mb, a keyword).
class CacheBudgetError : public IoError {
public:
    using IoError::IoError;
};

class BrickCache final : public BrickSource {
public:
    // `budgetBytes` bounds the decoded bricks held; it must fit at least two bricks.
    BrickCache(const BrickStoreReader& store, uint64_t budgetBytes);

    const VolumeInfo& volume() const override { return mStore.volume(); }
    const BrickLayout& layout() const override { return mStore.layout(); }
    int levelCount() const override { return mStore.header().levelCount; }
    std::span<const BrickRange> brickRanges() const override { return mRanges; }
    std::span<const SubBlockCode> subBlockCodesOf(int64_t id) const override;
    BrickHandle acquire(int64_t id) override;
    // Next to each other in the store's file (BrickStoreReader::readsTogether): bricks none of which
    // is held are read in one request (over a network, one GET where there were several).
    bool readsTogether(int64_t a, int64_t b) const override { return mStore.readsTogether(a, b); }
    std::vector<BrickHandle> acquireTogether(std::span<const int64_t> ids) override;
    // A store at a URL loads in the background: its request sent, no thread held while it waits
    // (BrickStoreReader::startStoredBricks); the bricks are decoded by finishAcquire's caller.
    // Bricks of `ids` held or loading already are left out (their handles from finishAcquire
    // are empty), and the others read in as many requests as runs of them lie apart in the file;
    // null only when every one is held.
    bool loadsInBackground() const override { return mStore.readsInBackground(); }
    std::unique_ptr<BrickLoad> startAcquire(std::span<const int64_t> ids, std::function<void()> arrived,
                                            const std::atomic<bool>* cancel) override;
    std::vector<BrickHandle> finishAcquire(BrickLoad& load) override;
    // At most the remote session's connections, and as many until the transfers have told how
    // many the link wants (a view's first requests would otherwise wait for their window to
    // grow: 16 at first made the small stores' views 1.02-1.04x as long).
    size_t loadsWanted() const override;
    // Loads started and not yet finished (the index's own requests are not counted).
    size_t loadsInFlight() const override;
    bool isResident(int64_t id) const override;
    int64_t brickCapacity() const override { return int64_t(mSlotCount); }

    CacheCounters counters() const;
    uint64_t budgetBytes() const { return mSlotCount * mBrickBytes; }
    uint64_t residentBytes() const;
    const BrickStoreReader& store() const { return mStore; }

protected:
    void release(int64_t id) override;

private:
    // Slot memory comes in chunks of about 32 MiB mapped with transparent huge pages: a
    // cold extraction otherwise spends a good part of its time faulting in 4 KiB pages.
    struct Chunk {
        unsigned char* bytes = nullptr;
        size_t size = 0;
        Chunk(size_t n);
        ~Chunk();
        Chunk(const Chunk&) = delete;
        Chunk& operator=(const Chunk&) = delete;
    };

    struct Slot {
        int64_t id = -1;
        int pins = 0;
        bool loading = false;
        unsigned char* samples = nullptr;
        std::list<size_t>::iterator lruPosition;  // valid while unpinned and holding a brick
    };

    size_t takeFreeSlot();
    // Under the lock: a slot for brick `id`, pinned and loading; and giving one back whose load
    // failed (the brick forgotten, its waiters woken).
    size_t claimLocked(int64_t id);
    void abandonLocked(size_t slot);
    // Bricks `ids` (two or more) none of which is held, claimed into slots (pinned, loading),
    // counted as misses; empty when one is held.
    std::vector<size_t> claimAllLocked(std::span<const int64_t> ids);
    // Decodes the stored bricks into their claimed slots and hands them out; on a failure the
    // slots are given back and the error is thrown.
    std::vector<BrickHandle> settle(std::span<const int64_t> ids, const std::vector<size_t>& slots,
                                    const std::vector<std::span<const unsigned char>>& stored, double readSeconds);

    const BrickStoreReader& mStore;
    std::vector<BrickRange> mRanges;
    size_t mBrickBytes;
    size_t mSlotCount;
    std::vector<Slot> mSlots;
    std::vector<std::unique_ptr<Chunk>> mChunks;
    size_t mSlotsPerChunk;
    size_t mSlotsAllocated = 0;
    std::unordered_map<int64_t, size_t> mSlotOfBrick;
    std::list<size_t> mLru;  // unpinned slots holding a brick, most recently used first
    CacheCounters mCounters;
    mutable std::mutex mMutex;
    // Per slot: the threads waiting for its load. One for all woke every waiter at every brick
    // loaded (the 16-32 readers of a remote store: most of a view's wake-ups).
    std::unique_ptr<std::condition_variable[]> mLoadedOf;
    std::atomic<size_t> mLoadsInFlight{0};
};

}  // namespace vdiso
