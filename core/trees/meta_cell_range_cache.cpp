#include "core/trees/meta_cell_range_cache.h"

namespace vdiso {

MetaCellRangeCache::Ranges MetaCellRangeCache::get(int64_t id, int64_t brick, BrickExtractor& extractor,
                                                   const void* samples) {
    {
        std::lock_guard lock(mMutex);
        const auto it = mEntries.find(id);
        if (it != mEntries.end() && it->second.metaCellSize == extractor.metaCellSize()) {
            mUse.splice(mUse.begin(), mUse, it->second.use);
            return it->second.ranges;
        }
    }
    // Computed outside the lock: strips computing the same brick at once both do the work.
    auto ranges = std::make_shared<std::vector<BrickRange>>();
    extractor.metaCellRanges(brick, samples, *ranges);
    std::lock_guard lock(mMutex);
    if (mMaxBricks == 0) return ranges;
    const auto it = mEntries.find(id);
    if (it != mEntries.end()) {
        it->second.ranges = ranges;
        it->second.metaCellSize = extractor.metaCellSize();
        mUse.splice(mUse.begin(), mUse, it->second.use);
        return ranges;
    }
    while (mEntries.size() >= mMaxBricks) {
        mEntries.erase(mUse.back());
        mUse.pop_back();
    }
    mUse.push_front(id);
    mEntries.emplace(id, Entry{ranges, extractor.metaCellSize(), mUse.begin()});
    return ranges;
}

size_t MetaCellRangeCache::size() const {
    std::lock_guard lock(mMutex);
    return mEntries.size();
}

}  // namespace vdiso
