// The meta-cell ranges of recently extracted bricks, kept from one view-dependent extraction
// to the next (core/trees/brick_memo.h): a brick's ranges are computed once while it stays in
// use, not once per frame, as the paper's meta-cell tree is built once. Computing them was a
// third of a distant view in memory.
//
// Holds up to `maxBricks` bricks' ranges (4 KB each for 8^3 meta-cells), dropping the least
// recently used. One cache per brick source; ranges computed for another meta-cell size are
// not returned. Thread-safe: the image strips of one extraction share it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/kernel/brick_extractor.h"
#include "core/trees/brick_memo.h"

namespace vdiso {

class MetaCellRangeCache {
public:
    using Ranges = BrickMemo<std::vector<BrickRange>>::Held;

    explicit MetaCellRangeCache(size_t maxBricks) : mMemo(maxBricks) {}

    // The ranges of source brick `id` as extractor.metaCellRanges gives them for `samples` (its
    // samples), computed on the first call. `brick`: its number in the extractor's layout
    // (its level's: core/brick_levels.h), `id` for level 0.
    Ranges get(int64_t id, int64_t brick, BrickExtractor& extractor, const void* samples) {
        return mMemo.get(id, extractor.metaCellSize(), [&] {
            std::vector<BrickRange> ranges;
            extractor.metaCellRanges(brick, samples, ranges);
            return ranges;
        });
    }

    size_t size() const { return mMemo.size(); }

private:
    BrickMemo<std::vector<BrickRange>> mMemo;
};

}  // namespace vdiso
