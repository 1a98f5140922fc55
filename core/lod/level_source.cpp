#include "core/lod/level_source.h"

#include "core/check.h"
#include "core/trees/sub_blocks.h"

namespace vdiso {

LevelSource::LevelSource(BrickSource& base, int level)
    : mBase(base), mLevel(base.levels().at(size_t(level))) {
    const size_t first = size_t(mLevel.firstBrick), count = size_t(mLevel.layout.brickCount());
    VDISO_CHECK_LE(first + count, base.brickRanges().size());
    mRanges = base.brickRanges().subspan(first, count);
}

}  // namespace vdiso
