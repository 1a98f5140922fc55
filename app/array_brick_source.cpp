#include "app/array_brick_source.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/interrupt.h"

namespace vdiso {

namespace {

// Min and max of the samples at the corners of brick `c`'s cells, as the store type holds them.
template <class S>
BrickRange measure(const StridedSamples& s, int64_t firstRow, const BrickLayout& layout, const Dims3& c) {
    const auto* base = static_cast<const unsigned char*>(s.data);
    S lo = std::numeric_limits<S>::max(), hi = std::numeric_limits<S>::lowest();
    bool nan = false;
    int64_t first[3], count[3];
    for (int a = 0; a < 3; ++a) {
        first[a] = c[a] * layout.brickSize;
        count[a] = layout.cellsOnAxis(a, c[a]) + 1;
    }
    // One row at a time: a typed loop the compiler vectorises when samples along x are adjacent.
    auto scan = [&](auto at) {
        for (int64_t z = first[2]; z < first[2] + count[2]; ++z)
            for (int64_t y = first[1]; y < first[1] + count[1]; ++y) {
                const unsigned char* row = base + (z - firstRow) * s.strides[2] + y * s.strides[1] + first[0] * s.strides[0];
                S rowLo = lo, rowHi = hi;
                for (int64_t x = 0; x < count[0]; ++x) {
                    const S v = at(row, x);
                    if constexpr (std::is_floating_point_v<S>)
                        if (v != v) {
                            nan = true;
                            continue;
                        }
                    rowLo = v < rowLo ? v : rowLo;
                    rowHi = v > rowHi ? v : rowHi;
                }
                lo = rowLo;
                hi = rowHi;
            }
    };
    if (s.strides[0] == int64_t(sizeof(S)) && reinterpret_cast<uintptr_t>(base) % alignof(S) == 0 &&
        s.strides[1] % int64_t(alignof(S)) == 0 && s.strides[2] % int64_t(alignof(S)) == 0)
        scan([](const unsigned char* row, int64_t x) { return reinterpret_cast<const S*>(row)[x]; });
    else
        scan([&](const unsigned char* row, int64_t x) {
            S v;
            std::memcpy(&v, row + x * s.strides[0], sizeof v);
            return v;
        });
    if (nan && lo > hi) return {NAN, NAN};
    // The range of the converted samples: convert the two ends as the samples are converted.
    float ends[2];
    S raw[2] = {lo, hi};
    decodeSamples(raw, s.type, false, 2, ends, ScalarType::F32);
    return {ends[0], ends[1]};
}

}  // namespace

ArrayBrickSource::ArrayBrickSource(const StridedSamples& samples, int brickSize, const glm::dvec3& spacing,
                                   int threads)
    : ArrayBrickSource(samples, 0, samples.dims[2], brickSize, spacing, threads) {}

ArrayBrickSource::ArrayBrickSource(const StridedSamples& rows, int64_t firstRow, int64_t volumeDepth, int brickSize,
                                   const glm::dvec3& spacing, int threads)
    : mSamples(rows), mFirstRow(firstRow) {
    const Dims3 dims{rows.dims[0], rows.dims[1], volumeDepth};
    if (const std::string problem = volumeDimsProblem(dims); !problem.empty())
        throw std::invalid_argument(problem);
    if (firstRow < 0 || firstRow + rows.dims[2] > volumeDepth)
        throw std::logic_error("ArrayBrickSource: rows beyond the volume's");
    mInfo.dims = dims;
    mInfo.type = storeTypeFor(rows.type, false);
    mInfo.spacing = spacing;
    mLayout = BrickLayout(dims, brickSize);
    if (const std::string problem = brickLayoutProblem(mLayout); !problem.empty())
        throw std::invalid_argument(problem);
    mRanges.assign(size_t(mLayout.brickCount()), kNoRange);
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    arena.execute([&] {
        tbb::parallel_for(int64_t(0), mLayout.brickCount(), [&](int64_t id) {
            const Dims3 c = mLayout.brickCoord(id);
            if (!holdsLayer(c[2])) return;
            throwIfInterrupted("the array");  // a pass over all of it: stopped within a brick
            mRanges[size_t(id)] = visitFileScalar(rows.type, [&](auto zero) {
                return measure<decltype(zero)>(mSamples, mFirstRow, mLayout, c);
            });
        });
    });
}

bool ArrayBrickSource::holdsLayer(int64_t brickZ) const {
    const int64_t first = mLayout.clampSample(2, mLayout.firstSample(brickZ));
    const int64_t last = mLayout.clampSample(2, mLayout.firstSample(brickZ) + mLayout.side() - 1);
    return first >= mFirstRow && last < mFirstRow + mSamples.dims[2];
}

void ArrayBrickSource::gather(int64_t id, unsigned char* brick) const {
    const Dims3 c = mLayout.brickCoord(id);
    if (!holdsLayer(c[2])) throw std::logic_error("ArrayBrickSource: brick " + std::to_string(id) + " lies beyond the rows held");
    const int side = mLayout.side();
    const size_t inBytes = fileScalarSize(mSamples.type), outBytes = scalarSize(mInfo.type);
    const auto* base = static_cast<const unsigned char*>(mSamples.data);
    std::vector<unsigned char> gathered(size_t(side) * inBytes);
    unsigned char* row = gathered.data();
    const int64_t x0 = mLayout.firstSample(c[0]);
    const bool contiguous = mSamples.strides[0] == int64_t(inBytes);
    const bool sameType = fileScalarOf(mInfo.type) == mSamples.type;
    for (int lz = 0; lz < side; ++lz) {
        const int64_t z = mLayout.clampSample(2, mLayout.firstSample(c[2]) + lz) - mFirstRow;
        for (int ly = 0; ly < side; ++ly) {
            const int64_t y = mLayout.clampSample(1, mLayout.firstSample(c[1]) + ly);
            const unsigned char* line = base + z * mSamples.strides[2] + y * mSamples.strides[1];
            unsigned char* out = brick + (size_t(lz) * side + ly) * side * outBytes;
            // Inside the volume on x with adjacent samples: the row as it lies (the common case).
            if (contiguous && x0 >= 0 && x0 + side <= mLayout.dims[0]) {
                const unsigned char* in = line + x0 * int64_t(inBytes);
                if (sameType) std::memcpy(out, in, size_t(side) * inBytes);
                else decodeSamples(in, mSamples.type, false, size_t(side), out, mInfo.type);
                continue;
            }
            for (int lx = 0; lx < side; ++lx)
                std::memcpy(row + lx * inBytes, line + mLayout.clampSample(0, x0 + lx) * mSamples.strides[0], inBytes);
            decodeSamples(row, mSamples.type, false, size_t(side), out, mInfo.type);
        }
    }
}

BrickHandle ArrayBrickSource::acquire(int64_t id) {
    std::vector<unsigned char> buffer;
    {
        std::lock_guard lock(mMutex);
        if (auto it = mPinned.find(id); it != mPinned.end()) {
            ++it->second.count;
            return BrickHandle(this, id, it->second.samples.data());
        }
        if (!mFree.empty()) {
            buffer = std::move(mFree.back());
            mFree.pop_back();
        }
    }
    buffer.resize(size_t(mLayout.samplesPerBrick()) * scalarSize(mInfo.type));
    gather(id, buffer.data());
    std::lock_guard lock(mMutex);
    auto [it, inserted] = mPinned.try_emplace(id);
    if (inserted) it->second.samples = std::move(buffer);
    else mFree.push_back(std::move(buffer));  // another thread gathered it meanwhile
    ++it->second.count;
    return BrickHandle(this, id, it->second.samples.data());
}

bool ArrayBrickSource::isResident(int64_t) const { return true; }  // nothing to read ahead

void ArrayBrickSource::release(int64_t id) {
    std::lock_guard lock(mMutex);
    auto it = mPinned.find(id);
    if (it == mPinned.end() || --it->second.count > 0) return;
    mFree.push_back(std::move(it->second.samples));
    mPinned.erase(it);
}

}  // namespace vdiso
