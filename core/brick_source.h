// The seam between algorithms and storage: "give me the samples of brick b".
//
// core never opens a file. Extractors see a volume as its brick layout, each brick's value
// range (from the store's index, known without reading the brick), and bricks acquired on
// demand: (B+3)^3 samples of volume().type in the layout of core/brick_layout.h. The cache
// (cache/brick_cache.h) implements it over the store reader; tests implement it in memory.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "core/brick_layout.h"
#include "core/brick_levels.h"
#include "core/volume.h"

namespace vdiso {

struct BrickRange {
    float minValue, maxValue;
};
// The range of no sample, which holds no isovalue; the union of two ranges (a NaN end is left out).
constexpr BrickRange kNoRange{INFINITY, -INFINITY};
inline BrickRange unite(const BrickRange& a, const BrickRange& b) {
    return {std::min(a.minValue, b.minValue), std::max(a.maxValue, b.maxValue)};
}

// The range of one sub-block of a brick, coded in two bytes (core/trees/sub_blocks.h).
struct SubBlockCode {
    uint8_t lo = 255, hi = 0;
};

class BrickSource;

// A brick's samples, valid while the handle lives (the source keeps the brick pinned).
class BrickHandle {
public:
    BrickHandle() = default;
    BrickHandle(BrickSource* source, int64_t id, const void* samples)
        : mSource(source), mId(id), mSamples(samples) {}
    BrickHandle(BrickHandle&& o) noexcept { *this = std::move(o); }
    BrickHandle& operator=(BrickHandle&& o) noexcept;
    BrickHandle(const BrickHandle&) = delete;
    BrickHandle& operator=(const BrickHandle&) = delete;
    ~BrickHandle() { release(); }

    const void* samples() const { return mSamples; }
    template <class T>
    const T* samplesAs() const { return static_cast<const T*>(mSamples); }
    int64_t id() const { return mId; }
    void release();

private:
    BrickSource* mSource = nullptr;
    int64_t mId = -1;
    const void* mSamples = nullptr;
};

// Bricks on their way (BrickSource::startAcquire); what it holds is the source's own.
class BrickLoad {
public:
    virtual ~BrickLoad() = default;
};

class BrickSource {
public:
    virtual ~BrickSource() = default;
    // Level 0: the volume and its bricks.
    virtual const VolumeInfo& volume() const = 0;
    virtual const BrickLayout& layout() const = 0;
    // Levels of detail held, level 0 included (core/brick_levels.h). Brick ids, brickRanges()
    // and subBlockCodesOf() run through every level, level 0's bricks first.
    virtual int levelCount() const { return 1; }
    std::vector<BrickLevel> levels() const { return brickLevels(volume(), layout().brickSize, levelCount()); }
    // Min and max of each brick's cell samples, indexed by brick id.
    virtual std::span<const BrickRange> brickRanges() const = 0;
    // The ranges of brick `id`'s kSubBlocksPerBrick sub-blocks (core/trees/sub_blocks.h), known
    // without reading the brick; empty when the source has none. May wait for them (a remote
    // store fetches them after its open) and throw as acquire does.
    virtual std::span<const SubBlockCode> subBlockCodesOf(int64_t) const { return {}; }
    // The samples of brick `id`, pinned until the handle is released. Throws on I/O failure.
    virtual BrickHandle acquire(int64_t id) = 0;
    // Whether bricks a and b are best acquired together (acquireTogether): they lie near each
    // other where the source reads them (in a store's file, one right after the other), so one
    // read brings both. False by default.
    virtual bool readsTogether(int64_t, int64_t) const { return false; }
    // Bricks `ids` (distinct, none in memory yet), each readsTogether with another of them,
    // acquired at once: one read where the source can. Handles in the order of `ids`. By
    // default, one acquire after another.
    virtual std::vector<BrickHandle> acquireTogether(std::span<const int64_t> ids);
    // Acquires that hold no thread while the bricks are on their way (a store at a URL, whose
    // requests wait a round trip). startAcquire(ids, arrived, cancel) begins acquireTogether(ids)
    // and returns at once; `arrived` is called once, on any thread, possibly before startAcquire
    // returns (quick: it may note and wake, not call the source), when finishAcquire will not
    // wait. finishAcquire decodes and gives the handles in the order of `ids`, an empty one for
    // a brick that was held or loading already (left out of the load), or throws what acquire
    // throws. Every load started must be finished before the source goes, wanted or not
    // (`cancel`, once set, makes its requests end sooner). Null from startAcquire: every brick of
    // `ids` is held or loading already. Sources without them (loadsInBackground false) return
    // null always.
    virtual bool loadsInBackground() const { return false; }
    virtual std::unique_ptr<BrickLoad> startAcquire(std::span<const int64_t> ids, std::function<void()> arrived,
                                                    const std::atomic<bool>* cancel) {
        (void)ids, (void)arrived, (void)cancel;
        return nullptr;
    }
    virtual std::vector<BrickHandle> finishAcquire(BrickLoad& load) {
        (void)load;
        return {};
    }
    // Loads worth having in flight now, over every reader of the source (the link's delay times
    // its bandwidth, as its transfers measure it), and how many are; 0, 0 for a source that
    // does not load in the background.
    virtual size_t loadsWanted() const { return 0; }
    virtual size_t loadsInFlight() const { return 0; }
    // Whether acquire(id) would find the brick in memory now (a hint: it may be gone by then).
    // Readers ahead skip such bricks. False when the source cannot tell.
    virtual bool isResident(int64_t) const { return false; }
    // How many bricks the source keeps in memory (its cache): a brick acquired again after
    // fewer others is not read again. By default all of them (a source in memory).
    virtual int64_t brickCapacity() const { return INT64_MAX; }

protected:
    friend class BrickHandle;
    virtual void release(int64_t id) = 0;
};

inline BrickHandle& BrickHandle::operator=(BrickHandle&& o) noexcept {
    if (this != &o) {
        release();
        mSource = o.mSource;
        mId = o.mId;
        mSamples = o.mSamples;
        o.mSource = nullptr;
        o.mSamples = nullptr;
    }
    return *this;
}

inline std::vector<BrickHandle> BrickSource::acquireTogether(std::span<const int64_t> ids) {
    std::vector<BrickHandle> handles;
    handles.reserve(ids.size());
    for (const int64_t id : ids) handles.push_back(acquire(id));
    return handles;
}

inline void BrickHandle::release() {
    if (mSource) mSource->release(mId);
    mSource = nullptr;
    mSamples = nullptr;
}

}  // namespace vdiso
