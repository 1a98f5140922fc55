// What the store's index says of a brick, measured where its samples lie: its range, its 4^3
// sub-block codes (core/trees/sub_blocks.h) and, for level 0, the fine histogram's counts of
// the samples it owns, read straight from the z-slices of its level (io/store/brick_encoder.h
// SliceWindow) in one pass over its cells' corner samples, without gathering the brick. Each
// row of corners is cut into the sub-blocks' segments (neighbours share their border corners),
// and the brick's range is the union of its sub-blocks'. The same values as measuring the
// gathered brick (measureSubBlocks, and the min and max over its cells' corners; NaN as -inf).
#pragma once

#include <bit>
#include <cstdint>

#include "core/brick_layout.h"
#include "core/trees/sub_blocks.h"
#include "io/store/brick_encoder.h"
#include "io/store/store_format.h"

namespace vdiso {

// The fine histogram's key of a sample (io/store/brick_encoder.h kFineHistogramBins): key
// order is value order for every type; exact for 8- and 16-bit integers; for floats the top 16
// bits of an order-preserving remapping of the IEEE bits, every NaN in key 0 (a bin that
// otherwise holds only NaN bit patterns), so that the keys of -inf (0x7f) and +inf (0xff80)
// hold nothing but infinities.
constexpr uint32_t kNanKey = 0;
constexpr uint32_t kNegativeInfinityKey = 0x7f;
constexpr uint32_t kPositiveInfinityKey = 0xff80;
inline uint32_t fineKey(uint8_t v) { return v; }
inline uint32_t fineKey(uint16_t v) { return v; }
inline uint32_t fineKey(int16_t v) { return uint32_t(int32_t(v) + 32768); }
inline uint32_t fineKey(float v) {
    if (v != v) return kNanKey;
    const uint32_t u = std::bit_cast<uint32_t>(v);
    return ((u & 0x80000000u) ? ~u : (u | 0x80000000u)) >> 16;
}

// Brick `coord` of `layout`, whose slices `window` holds: entry.minValue and maxValue, `codes`,
// and (unless the tables are null) one count per owned sample, alternating between the two
// tables along a row (runs of equal values do not wait on one counter).
void measureBrickInSlices(ScalarType type, const SliceWindow& window, const BrickLayout& layout, const Dims3& coord,
                          BrickEntry& entry, SubBlockCode codes[kSubBlocksPerBrick], uint64_t* histogramEven,
                          uint64_t* histogramOdd);

}  // namespace vdiso
