// The meta-cell ranges of recently extracted bricks, kept from one view-dependent extraction
// to the next (the frames of a moving camera, a viewer's clients): a brick's ranges are
// computed once while it stays in use, not once per frame, as the paper's meta-cell tree is
// built once. Computing them was a third of a distant view in memory.
//
// Holds up to `maxBricks` bricks' ranges (4 KB each for 8^3 meta-cells), dropping the least
// recently used. One cache per brick source and meta-cell size (ranges computed for another
// size are not returned). Thread-safe: the image strips of one extraction share it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "core/kernel/brick_extractor.h"

namespace vdiso {

class MetaCellRangeCache {
public:
    using Ranges = std::shared_ptr<const std::vector<BrickRange>>;

    explicit MetaCellRangeCache(size_t maxBricks) : mMaxBricks(maxBricks) {}

    // The ranges of source brick `id` as extractor.metaCellRanges gives them for `samples` (its
    // samples), computed on the first call. `brick`: its number in the extractor's layout
    // (its level's: core/brick_levels.h), `id` for level 0.
    Ranges get(int64_t id, int64_t brick, BrickExtractor& extractor, const void* samples);

    size_t size() const;

private:
    struct Entry {
        Ranges ranges;
        int metaCellSize;
        std::list<int64_t>::iterator use;
    };
    size_t mMaxBricks;
    std::unordered_map<int64_t, Entry> mEntries;
    std::list<int64_t> mUse;  // most recent first
    mutable std::mutex mMutex;
};

}  // namespace vdiso
