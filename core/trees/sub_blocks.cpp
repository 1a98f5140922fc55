#include "core/trees/sub_blocks.h"

#include <algorithm>
#include <cmath>

#include "core/kernel/iso.h"

namespace vdiso {

namespace {

constexpr int kSteps = 255;

double decodeStep(int step, const BrickRange& brick) {
    return double(brick.minValue) + (double(brick.maxValue) - double(brick.minValue)) * step / kSteps;
}

}  // namespace

SubBlockCode encodeSubBlockRange(double lo, double hi, const BrickRange& brick) {
    const double width = double(brick.maxValue) - double(brick.minValue);
    // Infinite or NaN samples (f32): the brick's whole range, which holds whatever they do.
    if (!std::isfinite(width) || !std::isfinite(lo) || !std::isfinite(hi)) return {0, kSteps};
    if (!(width > 0)) return {0, 0};  // a constant brick: every range is the one value
    int stepLo = std::clamp(int(std::floor((lo - brick.minValue) / width * kSteps)), 0, kSteps);
    int stepHi = std::clamp(int(std::ceil((hi - brick.minValue) / width * kSteps)), 0, kSteps);
    // Rounding in the division can land a step on the wrong side: step outward until the
    // decoded range (as decodeSubBlockRange rounds it) contains [lo, hi].
    while (stepLo > 0 && decodeSubBlockRange({uint8_t(stepLo), uint8_t(kSteps)}, brick).minValue > lo)
        --stepLo;
    while (stepHi < kSteps && decodeSubBlockRange({0, uint8_t(stepHi)}, brick).maxValue < hi)
        ++stepHi;
    return {uint8_t(stepLo), uint8_t(stepHi)};
}

BrickRange decodeSubBlockRange(SubBlockCode code, const BrickRange& brick) {
    if (code.lo == 0 && code.hi == kSteps) return brick;
    const double lo = decodeStep(code.lo, brick), hi = decodeStep(code.hi, brick);
    float loF = float(lo), hiF = float(hi);
    if (double(loF) > lo) loF = std::nextafter(loF, -INFINITY);
    if (double(hiF) < hi) hiF = std::nextafter(hiF, INFINITY);
    // The ends of the brick's own range are exact.
    if (code.lo == 0) loF = brick.minValue;
    if (code.hi == kSteps) hiF = brick.maxValue;
    return {loF, hiF};
}

void measureSubBlocks(ScalarType type, const void* samples, const BrickLayout& layout,
                      const Dims3& coord, const BrickRange& brick,
                      SubBlockCode out[kSubBlocksPerBrick]) {
    const int C = subBlockCells(layout.brickSize), side = layout.side();
    int cells[3];
    for (int a = 0; a < 3; ++a) cells[a] = layout.cellsOnAxis(a, coord[a]);
    visitScalarType(type, [&](auto zero) {
        using T = decltype(zero);
        const T* s = static_cast<const T*>(samples);
        for (int c = 0; c < kSubBlocksPerAxis; ++c)
            for (int b = 0; b < kSubBlocksPerAxis; ++b)
                for (int a = 0; a < kSubBlocksPerAxis; ++a) {
                    SubBlockCode& code = out[(c * kSubBlocksPerAxis + b) * kSubBlocksPerAxis + a];
                    const int first[3] = {a * C, b * C, c * C};
                    int last[3];  // last corner sample, in cells from the brick's first
                    bool hasCells = true;
                    for (int k = 0; k < 3; ++k) {
                        last[k] = std::min(first[k] + C, cells[k]);
                        hasCells = hasCells && first[k] < last[k];
                    }
                    if (!hasCells) {
                        code = SubBlockCode{};
                        continue;
                    }
                    // NaN samples (f32) count as -inf, as in the brick's own range
                    // (core/kernel/iso.h).
                    T lo = rangeValue(s[BrickLayout::cornerIndex(side, first[0], first[1], first[2])]);
                    T hi = lo;
                    for (int z = first[2]; z <= last[2]; ++z)
                        for (int y = first[1]; y <= last[1]; ++y) {
                            const T* row = s + BrickLayout::cornerIndex(side, 0, y, z);
                            for (int x = first[0]; x <= last[0]; ++x) {
                                const T v = rangeValue(row[x]);
                                lo = v < lo ? v : lo;
                                hi = v > hi ? v : hi;
                            }
                        }
                    code = encodeSubBlockRange(double(lo), double(hi), brick);
                }
    });
}

}  // namespace vdiso
