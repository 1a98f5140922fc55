// Sub-block ranges: the value range of each of a brick's 4^3 sub-blocks, known without reading
// the brick (the store keeps them in its index), so that view-dependent extraction can test a
// brick at a finer grain than its box before reading it. A brick's box is large against the
// surface it shows, most of all at silhouettes; testing its active sub-blocks instead cuts the
// bricks read towards those that hold visible surface (docs/design.md, "Memory and reads").
//
// Sub-block (a, b, c) owns the brick's cells [a C, (a + 1) C) x [b C, ...) x [c C, ...) with
// C = ceil(B / 4), fewer or none at the volume's far faces. Its range is the min and max of
// those cells' corner samples, in two bytes: quantized onto 255 steps of the brick's
// [min, max], the low end rounded down and the high end up, so the decoded range contains the
// true one. A sub-block without cells is coded {255, 0}, which decodes to an empty range.
// Numbered a fastest, like bricks.
#pragma once

#include <cstdint>

#include "core/brick_layout.h"
#include "core/brick_source.h"
#include "core/scalar_type.h"

namespace vdiso {

constexpr int kSubBlocksPerAxis = 4;
constexpr int kSubBlocksPerBrick = kSubBlocksPerAxis * kSubBlocksPerAxis * kSubBlocksPerAxis;

// Cells per sub-block side for bricks of B cells.
inline int subBlockCells(int brickSize) {
    return (brickSize + kSubBlocksPerAxis - 1) / kSubBlocksPerAxis;
}

// The code of [lo, hi] within the brick's range (which must contain it).
SubBlockCode encodeSubBlockRange(double lo, double hi, const BrickRange& brick);

// A range containing the one that was encoded; empty (min > max, or min == max) when the
// sub-block has no cells.
BrickRange decodeSubBlockRange(SubBlockCode code, const BrickRange& brick);

// Measures the sub-blocks of brick `coord` from its samples ((B+3)^3 of `type`, laid out as
// core/brick_layout.h says), whose cells' range is `brick`.
void measureSubBlocks(ScalarType type, const void* samples, const BrickLayout& layout,
                      const Dims3& coord, const BrickRange& brick,
                      SubBlockCode out[kSubBlocksPerBrick]);

}  // namespace vdiso
