// A BrickSource over samples already in memory, in any strided layout and any file scalar type:
// what meshing an array in place runs on (the Python module's marching_cubes), without a copy
// of the volume. The samples are converted to the store type that holds them
// (io/readers/sample_decode.h storeTypeFor: i8 -> i16, i32/u32/f64 -> f32) brick by brick as bricks are
// acquired; the brick ranges come from one pass over the samples at construction. The memory
// must stay valid and unchanged while the source lives. A source may hold a window of rows of a
// larger volume instead (what app/slab_extraction.h extracts a volume read in order with).
#pragma once

#include <array>
#include <cstdint>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "core/brick_source.h"
#include "io/readers/sample_decode.h"

namespace vdiso {

struct StridedSamples {
    const void* data = nullptr;
    FileScalar type = FileScalar::U8;
    Dims3 dims{0, 0, 0};              // x, y, z: x the axis the kernel walks fastest
    std::array<int64_t, 3> strides{}; // bytes from a sample to the next along x, y and z
};

class ArrayBrickSource final : public BrickSource {
public:
    // Throws std::invalid_argument for dimensions outside core/volume.h's limits. `threads`
    // measure the brick ranges (0: TBB's default).
    ArrayBrickSource(const StridedSamples& samples, int brickSize, const glm::dvec3& spacing, int threads);
    // Over the rows (z) [firstRow, firstRow + rows.dims[2]) of a volume `volumeDepth` samples deep,
    // its x and y those of `rows`: the bricks whose samples, ghost rows included, lie in those
    // rows are measured and may be acquired (holds()); the others have the empty range
    // {+inf, -inf}, which holds no isovalue, and acquiring one throws std::logic_error.
    ArrayBrickSource(const StridedSamples& rows, int64_t firstRow, int64_t volumeDepth, int brickSize,
                     const glm::dvec3& spacing, int threads);

    // Whether the bricks of layer `brickZ` (brick coordinate z) lie in the rows held.
    bool holdsLayer(int64_t brickZ) const;

    const VolumeInfo& volume() const override { return mInfo; }
    const BrickLayout& layout() const override { return mLayout; }
    std::span<const BrickRange> brickRanges() const override { return mRanges; }
    BrickHandle acquire(int64_t id) override;
    bool isResident(int64_t id) const override;

protected:
    void release(int64_t id) override;

private:
    void gather(int64_t id, unsigned char* brick) const;

    StridedSamples mSamples;
    int64_t mFirstRow = 0;  // the volume's row that mSamples' row 0 is
    VolumeInfo mInfo;
    BrickLayout mLayout;
    std::vector<BrickRange> mRanges;
    struct Pinned {
        std::vector<unsigned char> samples;
        int count = 0;
    };
    mutable std::mutex mMutex;
    std::unordered_map<int64_t, Pinned> mPinned;
    std::vector<std::vector<unsigned char>> mFree;  // buffers of released bricks, reused
};

}  // namespace vdiso
