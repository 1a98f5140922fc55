#include "core/clock.h"
#include "cache/brick_cache.h"

#include <algorithm>
#include <chrono>
#include <new>
#include <stdexcept>
#include <string>

#include "core/huge_pages.h"
#include "io/error.h"
#include "io/remote/remote_file.h"

namespace vdiso {


std::span<const SubBlockCode> BrickCache::subBlockCodesOf(int64_t id) const { return mStore.subBlockCodesOf(id); }

BrickCache::Chunk::Chunk(size_t n) : bytes(static_cast<unsigned char*>(mapHugePages(n))), size(n) {}

BrickCache::Chunk::~Chunk() { unmapHugePages(bytes, size); }

BrickCache::BrickCache(const BrickStoreReader& store, uint64_t budgetBytes)
    : mStore(store), mBrickBytes(store.brickBytes()) {
    mSlotCount = size_t(budgetBytes / mBrickBytes);
    if (mSlotCount < 2)
        throw std::invalid_argument("cache budget of " + std::to_string(budgetBytes >> 20) +
                                    " MB cannot hold two bricks of " +
                                    std::to_string(mBrickBytes >> 10) + " KB");
    // Never more slots than bricks: a budget larger than the volume allocates only what it uses.
    mSlotCount = std::min<size_t>(mSlotCount, store.index().size());
    mSlots.resize(mSlotCount);
    mLoadedOf = std::make_unique<std::condition_variable[]>(mSlotCount);
    mSlotsPerChunk = std::max<size_t>(1, (32u << 20) / mBrickBytes);
    mRanges.reserve(store.index().size());
    for (const BrickEntry& e : store.index()) mRanges.push_back({e.minValue, e.maxValue});
}

size_t BrickCache::takeFreeSlot() {
    if (mSlotsAllocated < mSlotCount) {
        const size_t within = mSlotsAllocated % mSlotsPerChunk;
        if (within == 0) {
            const size_t slots = std::min(mSlotsPerChunk, mSlotCount - mSlotsAllocated);
            try {
                mChunks.push_back(std::make_unique<Chunk>(slots * mBrickBytes));
            } catch (const std::bad_alloc&) {  // said in words, with the store and the budget
                throw CacheBudgetError(mStore.path() + ": the brick cache cannot get " +
                                       std::to_string((slots * mBrickBytes) >> 20) + " MB more memory, at " +
                                       std::to_string((mSlotsAllocated * mBrickBytes) >> 20) +
                                       " MB of its budget of " + std::to_string((mSlotCount * mBrickBytes) >> 20) +
                                       " MB: lower the budget");
            }
        }
        mSlots[mSlotsAllocated].samples = mChunks.back()->bytes + within * mBrickBytes;
        return mSlotsAllocated++;
    }
    if (mLru.empty())
        throw CacheBudgetError(mStore.path() + ": all " + std::to_string(mSlotCount) +
                               " bricks of the brick cache's budget are in use: raise the budget");
    const size_t slot = mLru.back();
    mLru.pop_back();
    mSlotOfBrick.erase(mSlots[slot].id);
    mSlots[slot].id = -1;
    ++mCounters.evictions;
    return slot;
}

bool BrickCache::isResident(int64_t id) const {
    std::lock_guard lock(mMutex);
    const auto found = mSlotOfBrick.find(id);
    return found != mSlotOfBrick.end() && !mSlots[found->second].loading;
}

BrickHandle BrickCache::acquire(int64_t id) {
    std::unique_lock lock(mMutex);
    ++mCounters.requests;
    auto found = mSlotOfBrick.find(id);
    if (found != mSlotOfBrick.end()) {
        const size_t slot = found->second;
        Slot& s = mSlots[slot];
        if (s.pins++ == 0) mLru.erase(s.lruPosition);
        ++mCounters.hits;
        mLoadedOf[slot].wait(lock, [&] { return !mSlots[slot].loading; });
        if (mSlots[slot].id != id) {
            // Another thread's load of this brick failed: give the slot back and try the read
            // ourselves, so this caller gets the error (or the brick) first-hand.
            if (--mSlots[slot].pins == 0) {
                mLru.push_back(slot);
                mSlots[slot].lruPosition = std::prev(mLru.end());
            }
            lock.unlock();
            return acquire(id);
        }
        return BrickHandle(this, id, mSlots[slot].samples);
    }
    ++mCounters.misses;
    const size_t slot = claimLocked(id);
    Slot& s = mSlots[slot];
    lock.unlock();

    double readSeconds = 0, decodeSeconds = 0;
    size_t storedBytes = 0;
    try {
        auto start = Clock::now();
        const std::span<const unsigned char> stored = mStore.readStoredBrick(id);
        storedBytes = stored.size();
        readSeconds = secondsSince(start);
        start = Clock::now();
        mStore.decodeBrick(id, stored, s.samples);
        decodeSeconds = secondsSince(start);
    } catch (...) {
        lock.lock();
        abandonLocked(slot);
        throw;
    }
    lock.lock();
    s.loading = false;
    mCounters.readSeconds += readSeconds;
    mCounters.decodeSeconds += decodeSeconds;
    mCounters.bytesRead += storedBytes;
    mLoadedOf[slot].notify_all();
    return BrickHandle(this, id, s.samples);
}

size_t BrickCache::claimLocked(int64_t id) {
    const size_t slot = takeFreeSlot();
    Slot& s = mSlots[slot];
    s.id = id;
    s.pins = 1;
    s.loading = true;
    mSlotOfBrick[id] = slot;
    return slot;
}

void BrickCache::abandonLocked(size_t slot) {
    // The slot holds nothing valid: forget the brick, free the slot for the next miss.
    Slot& s = mSlots[slot];
    mSlotOfBrick.erase(s.id);
    s.id = -1;
    s.loading = false;
    if (--s.pins == 0) {
        mLru.push_back(slot);
        s.lruPosition = std::prev(mLru.end());
    }
    mLoadedOf[slot].notify_all();
}

std::vector<size_t> BrickCache::claimAllLocked(std::span<const int64_t> ids) {
    std::vector<size_t> slots;
    if (ids.size() < 2) return slots;
    for (const int64_t id : ids)
        if (mSlotOfBrick.count(id) > 0) return slots;
    try {
        for (const int64_t id : ids) slots.push_back(claimLocked(id));
    } catch (...) {
        for (const size_t slot : slots) abandonLocked(slot);
        throw;
    }
    mCounters.requests += ids.size();
    mCounters.misses += ids.size();
    return slots;
}

std::vector<BrickHandle> BrickCache::settle(std::span<const int64_t> ids, const std::vector<size_t>& slots,
                                            const std::vector<std::span<const unsigned char>>& stored,
                                            double readSeconds) {
    const size_t count = ids.size();
    double decodeSeconds = 0;
    size_t storedBytes = 0;
    try {
        const auto start = Clock::now();
        for (size_t k = 0; k < count; ++k) {
            storedBytes += stored[k].size();
            mStore.decodeBrick(ids[k], stored[k], mSlots[slots[k]].samples);
        }
        decodeSeconds = secondsSince(start);
    } catch (...) {
        std::lock_guard lock(mMutex);
        for (const size_t slot : slots) abandonLocked(slot);
        throw;
    }
    std::vector<BrickHandle> handles;
    handles.reserve(count);
    std::lock_guard lock(mMutex);
    for (size_t k = 0; k < count; ++k) {
        mSlots[slots[k]].loading = false;
        mLoadedOf[slots[k]].notify_all();
        handles.emplace_back(this, ids[k], mSlots[slots[k]].samples);
    }
    mCounters.readSeconds += readSeconds;
    mCounters.decodeSeconds += decodeSeconds;
    mCounters.bytesRead += storedBytes;
    return handles;
}

std::vector<BrickHandle> BrickCache::acquireTogether(std::span<const int64_t> ids) {
    std::vector<size_t> slots;
    {
        std::lock_guard lock(mMutex);
        slots = claimAllLocked(ids);
    }
    if (slots.empty()) return BrickSource::acquireTogether(ids);  // one by one, as they are
    std::vector<std::span<const unsigned char>> stored;
    const auto start = Clock::now();
    try {
        stored = mStore.readStoredBricks(ids);
    } catch (...) {
        std::lock_guard lock(mMutex);
        for (const size_t slot : slots) abandonLocked(slot);
        throw;
    }
    return settle(ids, slots, stored, secondsSince(start));
}

namespace {

struct CacheLoad final : BrickLoad {
    std::vector<int64_t> ids;  // as asked for
    // Of them, those this load claimed (the others were held or loading), in runs stored one
    // after another in the file, each read in one request: run r is ids[at[r]...], its slots
    // likewise.
    std::vector<std::vector<size_t>> runs;  // positions in ids
    std::vector<size_t> slotAt;             // by position in ids; unused for those not claimed
    std::vector<std::shared_ptr<BrickStoreReader::StoredRead>> reads;  // shared: the store's own type
    Clock::time_point started;
};

}  // namespace

std::unique_ptr<BrickLoad> BrickCache::startAcquire(std::span<const int64_t> ids, std::function<void()> arrived,
                                                    const std::atomic<bool>* cancel) {
    if (!loadsInBackground()) return nullptr;
    auto load = std::make_unique<CacheLoad>();
    load->ids.assign(ids.begin(), ids.end());
    load->slotAt.assign(ids.size(), SIZE_MAX);
    std::vector<size_t> claimed;  // positions
    {
        std::lock_guard lock(mMutex);
        try {
            for (size_t k = 0; k < ids.size(); ++k)
                if (mSlotOfBrick.count(ids[k]) == 0) {
                    load->slotAt[k] = claimLocked(ids[k]);
                    claimed.push_back(k);
                }
        } catch (...) {
            for (const size_t k : claimed) abandonLocked(load->slotAt[k]);
            throw;
        }
        mCounters.requests += claimed.size();
        mCounters.misses += claimed.size();
    }
    if (claimed.empty()) return nullptr;
    // Everything the requests need made before the first is sent (nothing can fail after it:
    // a request started must not outlive the load it writes into).
    std::vector<std::vector<int64_t>> runIds;
    std::function<void()> runArrived;
    try {
        // In file order, cut where a brick does not follow the one before.
        std::sort(claimed.begin(), claimed.end(), [&](size_t a, size_t b) {
            return mStore.index()[size_t(ids[a])].offset < mStore.index()[size_t(ids[b])].offset;
        });
        for (size_t k = 0; k < claimed.size(); ++k) {
            if (k == 0 || !mStore.readsTogether(ids[claimed[k - 1]], ids[claimed[k]])) {
                load->runs.emplace_back();
                runIds.emplace_back();
            }
            load->runs.back().push_back(claimed[k]);
            runIds.back().push_back(ids[claimed[k]]);
        }
        load->reads.reserve(load->runs.size());
        // `arrived` once every run's read has.
        auto left = std::make_shared<std::atomic<size_t>>(load->runs.size());
        runArrived = [left, arrived = std::move(arrived)] {
            if (--*left == 0) arrived();
        };
    } catch (...) {
        std::lock_guard lock(mMutex);
        for (const size_t k : claimed) abandonLocked(load->slotAt[k]);
        throw;
    }
    load->started = Clock::now();
    ++mLoadsInFlight;
    // (startStoredBricks reports its failures through the read, to finishAcquire, not by throwing.)
    for (const std::vector<int64_t>& run : runIds) load->reads.push_back(mStore.startStoredBricks(run, runArrived, cancel));
    return load;
}

std::vector<BrickHandle> BrickCache::finishAcquire(BrickLoad& l) {
    auto& load = static_cast<CacheLoad&>(l);
    const double readSeconds = secondsSince(load.started);
    --mLoadsInFlight;
    std::vector<BrickHandle> handles(load.ids.size());
    std::exception_ptr failure;
    for (size_t r = 0; r < load.runs.size(); ++r) {
        const std::vector<size_t>& run = load.runs[r];
        std::vector<int64_t> runIds;
        std::vector<size_t> slots;
        for (const size_t k : run) {
            runIds.push_back(load.ids[k]);
            slots.push_back(load.slotAt[k]);
        }
        std::vector<std::span<const unsigned char>> stored;
        try {
            if (failure) std::rethrow_exception(failure);  // the runs after a failure given back too
            stored = mStore.finishStoredBricks(*load.reads[r]);
        } catch (...) {
            if (!failure) failure = std::current_exception();
            std::lock_guard lock(mMutex);
            for (const size_t slot : slots) abandonLocked(slot);
            continue;
        }
        try {
            std::vector<BrickHandle> settled = settle(runIds, slots, stored, r == 0 ? readSeconds : 0);
            for (size_t j = 0; j < run.size(); ++j) handles[run[j]] = std::move(settled[j]);
        } catch (...) {  // settle gave the slots back
            failure = std::current_exception();
        }
    }
    if (failure) std::rethrow_exception(failure);
    return handles;
}

size_t BrickCache::loadsWanted() const {
    const RemoteFile* remote = mStore.remote();
    return remote ? remote->wantedInFlight(size_t(remote->connections()), size_t(remote->connections())) : 0;
}

size_t BrickCache::loadsInFlight() const { return mLoadsInFlight.load(std::memory_order_relaxed); }

void BrickCache::release(int64_t id) {
    std::lock_guard lock(mMutex);
    const size_t slot = mSlotOfBrick.at(id);
    Slot& s = mSlots[slot];
    if (--s.pins == 0) {
        mLru.push_front(slot);
        s.lruPosition = mLru.begin();
    }
}

CacheCounters BrickCache::counters() const {
    std::lock_guard lock(mMutex);
    return mCounters;
}

uint64_t BrickCache::residentBytes() const {
    std::lock_guard lock(mMutex);
    return uint64_t(mSlotsAllocated) * mBrickBytes;
}

}  // namespace vdiso
