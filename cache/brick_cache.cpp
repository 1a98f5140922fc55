#include "core/clock.h"
#include "cache/brick_cache.h"

#include <algorithm>
#include <chrono>
#include <new>
#include <stdexcept>
#include <string>

#include "core/huge_pages.h"
#include "io/error.h"

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

std::vector<BrickHandle> BrickCache::acquireTogether(std::span<const int64_t> ids) {
    const int count = int(ids.size());
    std::vector<size_t> slots;
    {
        std::unique_lock lock(mMutex);
        bool anyHeld = false;
        for (const int64_t id : ids) anyHeld = anyHeld || mSlotOfBrick.count(id) > 0;
        if (!anyHeld && count > 1) {
            try {
                for (const int64_t id : ids) slots.push_back(claimLocked(id));
            } catch (...) {
                for (const size_t slot : slots) abandonLocked(slot);
                throw;
            }
            mCounters.requests += uint64_t(count);
            mCounters.misses += uint64_t(count);
        }
    }
    if (slots.empty()) return BrickSource::acquireTogether(ids);  // one by one, as they are

    double readSeconds = 0, decodeSeconds = 0;
    size_t storedBytes = 0;
    try {
        auto start = Clock::now();
        const std::vector<std::span<const unsigned char>> stored = mStore.readStoredBricks(ids);
        readSeconds = secondsSince(start);
        start = Clock::now();
        for (int k = 0; k < count; ++k) {
            storedBytes += stored[size_t(k)].size();
            mStore.decodeBrick(ids[size_t(k)], stored[size_t(k)], mSlots[slots[size_t(k)]].samples);
        }
        decodeSeconds = secondsSince(start);
    } catch (...) {
        std::lock_guard lock(mMutex);
        for (const size_t slot : slots) abandonLocked(slot);
        throw;
    }
    std::vector<BrickHandle> handles;
    std::lock_guard lock(mMutex);
    for (int k = 0; k < count; ++k) {
        mSlots[slots[size_t(k)]].loading = false;
        mLoadedOf[slots[size_t(k)]].notify_all();
        handles.emplace_back(this, ids[size_t(k)], mSlots[slots[size_t(k)]].samples);
    }
    mCounters.readSeconds += readSeconds;
    mCounters.decodeSeconds += decodeSeconds;
    mCounters.bytesRead += storedBytes;
    return handles;
}

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
